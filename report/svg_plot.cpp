#include "report/svg_plot.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

namespace sextant::tools {
namespace {

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

std::string tick_label(double v) {
  char b[32];
  if (std::abs(v) < 1e-12) return "0";
  if (std::abs(v) >= 1e4 || (std::abs(v) < 1e-2 && v != 0))
    std::snprintf(b, sizeof b, "%.1e", v);
  else
    std::snprintf(b, sizeof b, "%g", std::round(v * 1000) / 1000);
  return b;
}

// "Nice" tick spacing: 1, 2 or 5 times a power of ten, about n ticks over the range.
double nice_step(double range, int n) {
  const double raw = range / n;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

// A stable id for the plot's clip path and gradient, from its title and labels (no counter: output is reproducible).
std::string plot_id(const std::string& title, const std::string& x, const std::string& y) {
  uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (unsigned char c : title + "|" + x + "|" + y) h = (h ^ c) * 1099511628211ull;
  char b[24];
  std::snprintf(b, sizeof b, "p%016llx", static_cast<unsigned long long>(h));
  return b;
}

}  // namespace

std::string viridis(double t) {
  static const double stops[9][3] = {{68, 1, 84},    {71, 44, 122}, {59, 81, 139},  {44, 113, 142}, {33, 144, 141},
                                     {39, 173, 129}, {92, 200, 99}, {170, 220, 50}, {253, 231, 37}};
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * 8;
  const int i = std::min(7, static_cast<int>(t));
  const double f = t - i;
  char b[8];
  std::snprintf(b, sizeof b, "#%02x%02x%02x",
                static_cast<int>(std::lround(stops[i][0] + f * (stops[i + 1][0] - stops[i][0]))),
                static_cast<int>(std::lround(stops[i][1] + f * (stops[i + 1][1] - stops[i][1]))),
                static_cast<int>(std::lround(stops[i][2] + f * (stops[i + 1][2] - stops[i][2]))));
  return b;
}

Eigen::Vector4d robust_view(const std::vector<Eigen::Vector2d>& must_show, const std::vector<Eigen::Vector2d>& points,
                            double tail, double margin, double min_margin) {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const auto& p : must_show)
    if (p.allFinite())
      x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  std::vector<double> xs, ys;
  for (const auto& p : points)
    if (p.allFinite()) xs.push_back(p.x()), ys.push_back(p.y());
  if (!xs.empty()) {
    // Nearest-rank quantiles: with fewer than 1/tail points, no point is dropped.
    auto quantile = [](std::vector<double>& v, double q) {
      const size_t k = static_cast<size_t>(std::floor(q * static_cast<double>(v.size() - 1) + 0.5));
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
      return v[k];
    };
    const double lo = std::floor(tail * static_cast<double>(xs.size())) / static_cast<double>(xs.size());
    x0 = std::min(x0, quantile(xs, lo)), x1 = std::max(x1, quantile(xs, 1 - lo));
    y0 = std::min(y0, quantile(ys, lo)), y1 = std::max(y1, quantile(ys, 1 - lo));
  }
  if (!std::isfinite(x0)) return {0, 1, 0, 1};
  const double mx = std::max(min_margin, margin * (x1 - x0)), my = std::max(min_margin, margin * (y1 - y0));
  return {x0 - mx, x1 + mx, y0 - my, y1 + my};
}

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

SvgPlot::SvgPlot(std::string title, std::string x_label, std::string y_label, int width, int height)
    : title_(std::move(title)),
      x_label_(std::move(x_label)),
      y_label_(std::move(y_label)),
      width_(width),
      height_(height) {}

void SvgPlot::polyline(const std::vector<Eigen::Vector2d>& p, const std::string& color, const std::string& label,
                       double w) {
  if (!p.empty()) items_.push_back({Item::kLine, p, color, label, w, {}});
}

void SvgPlot::points(const std::vector<Eigen::Vector2d>& p, const std::string& color, const std::string& label,
                     double r) {
  if (!p.empty()) items_.push_back({Item::kPoints, p, color, label, r, {}});
}

void SvgPlot::ellipse(const Eigen::Vector2d& c, const Eigen::Matrix2d& cov, double k, const std::string& color) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (cov + cov.transpose()));
  const Eigen::Vector2d s = eig.eigenvalues().cwiseMax(0).cwiseSqrt() * k;
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i <= 48; ++i) {
    const double a = 2 * M_PI * i / 48;
    pts.push_back(c + eig.eigenvectors() * Eigen::Vector2d(s[0] * std::cos(a), s[1] * std::sin(a)));
  }
  items_.push_back({Item::kEllipse, pts, color, "", 1.0, {}});
}

void SvgPlot::histogram(const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color,
                        const std::string& label) {
  std::vector<Eigen::Vector2d> pts;  // (left edge, count) then the final right edge with 0
  for (size_t i = 0; i < counts.size(); ++i) pts.emplace_back(edges[i], counts[i]);
  if (!edges.empty()) pts.emplace_back(edges.back(), 0);
  if (!counts.empty()) items_.push_back({Item::kBars, pts, color, label, 1.0, {}});
}

void SvgPlot::colored_polyline(const std::vector<Eigen::Vector2d>& p, const std::vector<double>& values,
                               const std::string& value_label, double w) {
  if (p.size() < 2 || values.size() != p.size()) return;
  Item it{Item::kColoredLine, p, "", value_label, w, values};
  items_.push_back(std::move(it));
}

void SvgPlot::hline(double y, const std::string& color, const std::string& label) {
  if (std::isfinite(y)) items_.push_back({Item::kHLine, {Eigen::Vector2d(0, y)}, color, label, 1.5, {}});
}

void SvgPlot::hband(double lo, double hi, const std::string& color, const std::string& label) {
  if (std::isfinite(lo) && std::isfinite(hi))
    items_.push_back({Item::kBand, {Eigen::Vector2d(0, lo), Eigen::Vector2d(0, hi)}, color, label, 1.0, {}});
}

// Where the plot goes: margins, the plot area (pw x ph at (ml, mt)), the data range [x0, x1] x [y0, y1] shown, the
// range of the coloured lines' values, and the plot's id (for its clip path and gradient).
struct SvgPlot::Frame {
  bool colour_bar = false;
  double ml = 0, mr = 0, mt = 0, mb = 0, pw = 0, ph = 0;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  double vmin = 0, vmax = 0;
  std::string value_label, id;
  double X(double x) const { return ml + (x - x0) / (x1 - x0) * pw; }
  double Y(double y) const { return mt + ph - (y - y0) / (y1 - y0) * ph; }
};

std::string SvgPlot::render() const {
  const Frame f = frame();
  std::string s = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(width_) + "\" height=\"" +
                  std::to_string(height_) + "\" viewBox=\"0 0 " + std::to_string(width_) + " " +
                  std::to_string(height_) + "\" class=\"plot\" font-family=\"sans-serif\" font-size=\"11\">\n";
  s += "<rect x=\"0\" y=\"0\" width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s += "<text x=\"" + fmt(width_ / 2.0) + "\" y=\"20\" text-anchor=\"middle\" font-size=\"14\" font-weight=\"bold\">" +
       html_escape(title_) + "</text>\n";
  if (!subtitle_.empty())
    s += "<text x=\"" + fmt(width_ / 2.0) + "\" y=\"36\" text-anchor=\"middle\" fill=\"#555\">" +
         html_escape(subtitle_) + "</text>\n";
  render_axes(s, f);
  s += "<clipPath id=\"" + f.id + "-clip\"><rect x=\"" + fmt(f.ml) + "\" y=\"" + fmt(f.mt) + "\" width=\"" + fmt(f.pw) +
       "\" height=\"" + fmt(f.ph) + "\"/></clipPath>\n";
  s += "<g clip-path=\"url(#" + f.id + "-clip)\">\n";
  render_items(s, f);
  s += "</g>\n";
  if (f.colour_bar) render_colour_bar(s, f);
  render_legend(s, f);
  s += "</svg>\n";
  return s;
}

// Margins from what is drawn beside the plot (colour bar, subtitle, category labels); the data range from the items
// (bars from 0), padded, or the view set; widened on one axis for equal aspect.
SvgPlot::Frame SvgPlot::frame() const {
  Frame f;
  size_t longest_category = 0;
  for (const auto& it : items_) f.colour_bar = f.colour_bar || it.kind == Item::kColoredLine;
  for (const auto& c : categories_) longest_category = std::max(longest_category, c.size());
  f.ml = 70, f.mr = f.colour_bar ? 80 : 20, f.mt = subtitle_.empty() ? 34 : 48;
  f.mb = categories_.empty() ? 48 : std::min(140.0, 40.0 + 4.2 * static_cast<double>(longest_category));
  f.pw = width_ - f.ml - f.mr, f.ph = height_ - f.mt - f.mb;
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const auto& it : items_)
    for (const auto& p : it.pts) {
      if (!std::isfinite(p.x()) || !std::isfinite(p.y())) continue;
      if (it.kind != Item::kHLine && it.kind != Item::kBand) x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
    }
  for (const auto& it : items_)
    if (it.kind == Item::kBars) y0 = std::min(y0, 0.0);
  if (!std::isfinite(x0)) x0 = 0, x1 = 1;
  if (!std::isfinite(y0)) y0 = 0, y1 = 1;
  if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
  if (y1 - y0 < 1e-12) y0 -= 0.5, y1 += 0.5;
  if (has_view_) {
    x0 = view_[0], x1 = view_[1], y0 = view_[2], y1 = view_[3];
  } else {
    const double padx = 0.04 * (x1 - x0), pady = 0.06 * (y1 - y0);
    x0 -= padx, x1 += padx, y0 -= pady, y1 += pady;
  }
  if (equal_aspect_) {
    const double sx = f.pw / (x1 - x0), sy = f.ph / (y1 - y0);
    if (sx < sy) {
      const double c = 0.5 * (y0 + y1), h = f.ph / sx / 2;
      y0 = c - h, y1 = c + h;
    } else {
      const double c = 0.5 * (x0 + x1), h = f.pw / sy / 2;
      x0 = c - h, x1 = c + h;
    }
  }
  f.x0 = x0, f.x1 = x1, f.y0 = y0, f.y1 = y1;
  f.id = plot_id(title_, x_label_, y_label_);
  f.vmin = std::numeric_limits<double>::infinity(), f.vmax = -f.vmin;
  for (const auto& it : items_)
    if (it.kind == Item::kColoredLine) {
      for (double v : it.values)
        if (std::isfinite(v)) f.vmin = std::min(f.vmin, v), f.vmax = std::max(f.vmax, v);
      f.value_label = it.label;
    }
  if (!(f.vmax > f.vmin)) f.vmax = f.vmin + 1;
  return f;
}

// The plot's box, its grid with tick labels (or the category labels under it) and the axis labels.
void SvgPlot::render_axes(std::string& s, const Frame& f) const {
  const double ml = f.ml, mt = f.mt, pw = f.pw, ph = f.ph;
  s += "<rect x=\"" + fmt(ml) + "\" y=\"" + fmt(mt) + "\" width=\"" + fmt(pw) + "\" height=\"" + fmt(ph) +
       "\" fill=\"none\" stroke=\"#333\"/>\n";
  const double sx = nice_step(f.x1 - f.x0, 6), sy = nice_step(f.y1 - f.y0, 5);
  if (categories_.empty()) {
    for (double t = std::ceil(f.x0 / sx) * sx; t <= f.x1; t += sx)
      s += "<line x1=\"" + fmt(f.X(t)) + "\" y1=\"" + fmt(mt) + "\" x2=\"" + fmt(f.X(t)) + "\" y2=\"" + fmt(mt + ph) +
           "\" stroke=\"#e4e4e4\"/><text x=\"" + fmt(f.X(t)) + "\" y=\"" + fmt(mt + ph + 15) +
           "\" text-anchor=\"middle\">" + tick_label(t) + "</text>\n";
  } else {
    for (size_t k = 0; k < categories_.size(); ++k) {
      const double cx = f.X(static_cast<double>(k) + 0.45), cy = mt + ph + 12;
      s += "<text class=\"category\" x=\"" + fmt(cx) + "\" y=\"" + fmt(cy) +
           "\" text-anchor=\"end\" transform=\"rotate(-35 " + fmt(cx) + " " + fmt(cy) + ")\">" +
           html_escape(categories_[k]) + "</text>\n";
    }
  }
  for (double t = std::ceil(f.y0 / sy) * sy; t <= f.y1; t += sy)
    s += "<line x1=\"" + fmt(ml) + "\" y1=\"" + fmt(f.Y(t)) + "\" x2=\"" + fmt(ml + pw) + "\" y2=\"" + fmt(f.Y(t)) +
         "\" stroke=\"#e4e4e4\"/><text x=\"" + fmt(ml - 6) + "\" y=\"" + fmt(f.Y(t) + 4) + "\" text-anchor=\"end\">" +
         tick_label(t) + "</text>\n";
  s += "<text x=\"" + fmt(ml + pw / 2) + "\" y=\"" + fmt(height_ - 8.0) + "\" text-anchor=\"middle\">" +
       html_escape(x_label_) + "</text>\n";
  s += "<text transform=\"translate(16," + fmt(mt + ph / 2) + ") rotate(-90)\" text-anchor=\"middle\">" +
       html_escape(y_label_) + "</text>\n";
}

// The items, in the order they were added.
void SvgPlot::render_items(std::string& s, const Frame& f) const {
  const double ml = f.ml, pw = f.pw;
  for (const auto& it : items_) {
    if (it.kind == Item::kBand) {
      const double ya = f.Y(std::max(it.pts[0].y(), it.pts[1].y())), yb = f.Y(std::min(it.pts[0].y(), it.pts[1].y()));
      s += "<rect class=\"stat\" x=\"" + fmt(ml) + "\" y=\"" + fmt(ya) + "\" width=\"" + fmt(pw) + "\" height=\"" +
           fmt(yb - ya) + "\" fill=\"" + it.color + "\" fill-opacity=\"0.15\"/>\n";
    } else if (it.kind == Item::kHLine) {
      s += "<line class=\"stat\" x1=\"" + fmt(ml) + "\" y1=\"" + fmt(f.Y(it.pts[0].y())) + "\" x2=\"" + fmt(ml + pw) +
           "\" y2=\"" + fmt(f.Y(it.pts[0].y())) + "\" stroke=\"" + it.color +
           "\" stroke-width=\"1.5\" stroke-dasharray=\"6,4\"/>\n";
    } else if (it.kind == Item::kColoredLine) {
      // Runs of segments in the same one of 64 colour levels become one polyline.
      auto level = [&](size_t i) {
        const double v = 0.5 * (it.values[i] + it.values[i + 1]);
        return std::clamp(static_cast<int>((v - f.vmin) / (f.vmax - f.vmin) * 64), 0, 63);
      };
      size_t start = 0;
      while (start + 1 < it.pts.size()) {
        const int lv = level(start);
        size_t end = start + 1;
        while (end + 1 < it.pts.size() && level(end) == lv) ++end;
        s += "<polyline fill=\"none\" stroke=\"" + viridis((lv + 0.5) / 64.0) + "\" stroke-width=\"" + fmt(it.size) +
             "\" stroke-linecap=\"round\" class=\"series colored\" points=\"";
        for (size_t k = start; k <= end; ++k) s += fmt(f.X(it.pts[k].x())) + "," + fmt(f.Y(it.pts[k].y())) + " ";
        s += "\"/>\n";
        start = end;
      }
    } else if (it.kind == Item::kLine || it.kind == Item::kEllipse) {
      s += "<polyline fill=\"none\" stroke=\"" + it.color + "\" stroke-width=\"" + fmt(it.size) + "\" class=\"" +
           (it.kind == Item::kLine ? "series" : "ellipse") + "\" points=\"";
      for (const auto& p : it.pts) s += fmt(f.X(p.x())) + "," + fmt(f.Y(p.y())) + " ";
      s += "\"/>\n";
    } else if (it.kind == Item::kPoints) {
      for (const auto& p : it.pts)
        s += "<circle class=\"series\" cx=\"" + fmt(f.X(p.x())) + "\" cy=\"" + fmt(f.Y(p.y())) + "\" r=\"" +
             fmt(it.size) + "\" fill=\"" + it.color + "\"/>\n";
    } else {
      for (size_t i = 0; i + 1 < it.pts.size(); ++i) {
        const double xa = f.X(it.pts[i].x()), xb = f.X(it.pts[i + 1].x()), yt = f.Y(it.pts[i].y()), yb = f.Y(0);
        s += "<rect class=\"series\" x=\"" + fmt(xa) + "\" y=\"" + fmt(std::min(yt, yb)) + "\" width=\"" +
             fmt(std::max(0.5, xb - xa - 1)) + "\" height=\"" + fmt(std::abs(yb - yt)) + "\" fill=\"" + it.color +
             "\"/>\n";
      }
    }
  }
}

// The colour bar of the coloured lines' values, right of the plot.
void SvgPlot::render_colour_bar(std::string& s, const Frame& f) const {
  const double bx = f.ml + f.pw + 18, bw = 14, mt = f.mt, ph = f.ph;
  s += "<defs><linearGradient id=\"" + f.id + "-scale\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">";
  for (int k = 0; k <= 8; ++k) s += "<stop offset=\"" + fmt(k / 8.0) + "\" stop-color=\"" + viridis(k / 8.0) + "\"/>";
  s += "</linearGradient></defs>\n<rect class=\"colorbar\" x=\"" + fmt(bx) + "\" y=\"" + fmt(mt) + "\" width=\"" +
       fmt(bw) + "\" height=\"" + fmt(ph) + "\" fill=\"url(#" + f.id + "-scale)\"/>\n";
  s += "<text x=\"" + fmt(bx + bw + 3) + "\" y=\"" + fmt(mt + 8) + "\">" + tick_label(f.vmax) + "</text>\n";
  s += "<text x=\"" + fmt(bx + bw + 3) + "\" y=\"" + fmt(mt + ph) + "\">" + tick_label(f.vmin) + "</text>\n";
  s += "<text transform=\"translate(" + fmt(bx + bw + 14) + "," + fmt(mt + ph / 2) +
       ") rotate(-90)\" text-anchor=\"middle\">" + html_escape(f.value_label) + "</text>\n";
}

// The legend in the top right corner, as wide as its longest label (about 6.2 px per character at 11 px), on a
// translucent white box so the data under it stays visible.
void SvgPlot::render_legend(std::string& s, const Frame& f) const {
  size_t longest = 0, entries = 0;
  for (const auto& it : items_)
    if (!it.label.empty() && it.kind != Item::kColoredLine) longest = std::max(longest, it.label.size()), ++entries;
  if (entries == 0) return;
  const double lw = std::min(f.pw - 10, 26 + 6.2 * static_cast<double>(longest)), lx = f.ml + f.pw - lw - 4;
  const double lh = 16.0 * static_cast<double>(entries) + 6, top = legend_bottom_ ? f.mt + f.ph - lh - 3 : f.mt + 3;
  s += "<rect class=\"legend\" x=\"" + fmt(lx) + "\" y=\"" + fmt(top) + "\" width=\"" + fmt(lw) + "\" height=\"" +
       fmt(lh) + "\" fill=\"white\" fill-opacity=\"0.8\" stroke=\"#ccc\"/>\n";
  double ly = top + 14;
  for (const auto& it : items_) {
    if (it.label.empty() || it.kind == Item::kColoredLine) continue;
    s += "<rect x=\"" + fmt(lx + 5) + "\" y=\"" + fmt(ly - 9) + "\" width=\"12\" height=\"" +
         (it.kind == Item::kHLine ? "3" : "10") + "\" fill=\"" + it.color + "\"/><text x=\"" + fmt(lx + 22) +
         "\" y=\"" + fmt(ly) + "\">" + html_escape(it.label) + "</text>\n";
    ly += 16;
  }
}

}  // namespace sextant::tools
