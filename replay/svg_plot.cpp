#include "replay/svg_plot.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace sextant::replay {
namespace {

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

std::string tick_label(double v) {
  char b[32];
  if (std::abs(v) < 1e-12) return "0";
  if (std::abs(v) >= 1e4 || (std::abs(v) < 1e-2 && v != 0)) std::snprintf(b, sizeof b, "%.1e", v);
  else std::snprintf(b, sizeof b, "%g", std::round(v * 1000) / 1000);
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

}  // namespace

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

SvgPlot::SvgPlot(std::string title, std::string x_label, std::string y_label, int width, int height)
    : title_(std::move(title)), x_label_(std::move(x_label)), y_label_(std::move(y_label)), width_(width), height_(height) {}

void SvgPlot::polyline(const std::vector<Eigen::Vector2d>& p, const std::string& color, const std::string& label, double w) {
  if (!p.empty()) items_.push_back({Item::kLine, p, color, label, w});
}

void SvgPlot::points(const std::vector<Eigen::Vector2d>& p, const std::string& color, const std::string& label, double r) {
  if (!p.empty()) items_.push_back({Item::kPoints, p, color, label, r});
}

void SvgPlot::ellipse(const Eigen::Vector2d& c, const Eigen::Matrix2d& cov, double k, const std::string& color) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (cov + cov.transpose()));
  const Eigen::Vector2d s = eig.eigenvalues().cwiseMax(0).cwiseSqrt() * k;
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i <= 48; ++i) {
    const double a = 2 * M_PI * i / 48;
    pts.push_back(c + eig.eigenvectors() * Eigen::Vector2d(s[0] * std::cos(a), s[1] * std::sin(a)));
  }
  items_.push_back({Item::kEllipse, pts, color, "", 1.0});
}

void SvgPlot::histogram(const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color,
                        const std::string& label) {
  std::vector<Eigen::Vector2d> pts;  // (left edge, count) then the final right edge with 0
  for (size_t i = 0; i < counts.size(); ++i) pts.emplace_back(edges[i], counts[i]);
  if (!edges.empty()) pts.emplace_back(edges.back(), 0);
  if (!counts.empty()) items_.push_back({Item::kBars, pts, color, label, 1.0});
}

std::string SvgPlot::render() const {
  const double ml = 70, mr = 20, mt = 34, mb = 48;
  const double pw = width_ - ml - mr, ph = height_ - mt - mb;
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const auto& it : items_)
    for (const auto& p : it.pts) {
      x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
    }
  for (const auto& it : items_)
    if (it.kind == Item::kBars) y0 = std::min(y0, 0.0);
  if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
  if (y1 - y0 < 1e-12) y0 -= 0.5, y1 += 0.5;
  const double padx = 0.04 * (x1 - x0), pady = 0.06 * (y1 - y0);
  x0 -= padx, x1 += padx, y0 -= pady, y1 += pady;
  if (equal_aspect_) {
    const double sx = pw / (x1 - x0), sy = ph / (y1 - y0);
    if (sx < sy) {
      const double c = 0.5 * (y0 + y1), h = ph / sx / 2;
      y0 = c - h, y1 = c + h;
    } else {
      const double c = 0.5 * (x0 + x1), h = pw / sy / 2;
      x0 = c - h, x1 = c + h;
    }
  }
  auto X = [&](double x) { return ml + (x - x0) / (x1 - x0) * pw; };
  auto Y = [&](double y) { return mt + ph - (y - y0) / (y1 - y0) * ph; };
  std::string s = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(width_) + "\" height=\"" +
                  std::to_string(height_) + "\" viewBox=\"0 0 " + std::to_string(width_) + " " + std::to_string(height_) +
                  "\" class=\"plot\" font-family=\"sans-serif\" font-size=\"11\">\n";
  s += "<rect x=\"0\" y=\"0\" width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s += "<text x=\"" + fmt(width_ / 2.0) + "\" y=\"20\" text-anchor=\"middle\" font-size=\"14\" font-weight=\"bold\">" +
       html_escape(title_) + "</text>\n";
  s += "<rect x=\"" + fmt(ml) + "\" y=\"" + fmt(mt) + "\" width=\"" + fmt(pw) + "\" height=\"" + fmt(ph) +
       "\" fill=\"none\" stroke=\"#333\"/>\n";
  const double sx = nice_step(x1 - x0, 6), sy = nice_step(y1 - y0, 5);
  for (double t = std::ceil(x0 / sx) * sx; t <= x1; t += sx)
    s += "<line x1=\"" + fmt(X(t)) + "\" y1=\"" + fmt(mt) + "\" x2=\"" + fmt(X(t)) + "\" y2=\"" + fmt(mt + ph) +
         "\" stroke=\"#e4e4e4\"/><text x=\"" + fmt(X(t)) + "\" y=\"" + fmt(mt + ph + 15) + "\" text-anchor=\"middle\">" +
         tick_label(t) + "</text>\n";
  for (double t = std::ceil(y0 / sy) * sy; t <= y1; t += sy)
    s += "<line x1=\"" + fmt(ml) + "\" y1=\"" + fmt(Y(t)) + "\" x2=\"" + fmt(ml + pw) + "\" y2=\"" + fmt(Y(t)) +
         "\" stroke=\"#e4e4e4\"/><text x=\"" + fmt(ml - 6) + "\" y=\"" + fmt(Y(t) + 4) + "\" text-anchor=\"end\">" +
         tick_label(t) + "</text>\n";
  s += "<text x=\"" + fmt(ml + pw / 2) + "\" y=\"" + fmt(height_ - 10.0) + "\" text-anchor=\"middle\">" + html_escape(x_label_) + "</text>\n";
  s += "<text transform=\"translate(16," + fmt(mt + ph / 2) + ") rotate(-90)\" text-anchor=\"middle\">" + html_escape(y_label_) + "</text>\n";
  s += "<g clip-path=\"none\">\n";
  for (const auto& it : items_) {
    if (it.kind == Item::kLine || it.kind == Item::kEllipse) {
      s += "<polyline fill=\"none\" stroke=\"" + it.color + "\" stroke-width=\"" + fmt(it.size) + "\" class=\"" +
           (it.kind == Item::kLine ? "series" : "ellipse") + "\" points=\"";
      for (const auto& p : it.pts) s += fmt(X(p.x())) + "," + fmt(Y(p.y())) + " ";
      s += "\"/>\n";
    } else if (it.kind == Item::kPoints) {
      for (const auto& p : it.pts)
        s += "<circle class=\"series\" cx=\"" + fmt(X(p.x())) + "\" cy=\"" + fmt(Y(p.y())) + "\" r=\"" + fmt(it.size) +
             "\" fill=\"" + it.color + "\"/>\n";
    } else {
      for (size_t i = 0; i + 1 < it.pts.size(); ++i) {
        const double xa = X(it.pts[i].x()), xb = X(it.pts[i + 1].x()), yt = Y(it.pts[i].y()), yb = Y(0);
        s += "<rect class=\"series\" x=\"" + fmt(xa) + "\" y=\"" + fmt(std::min(yt, yb)) + "\" width=\"" +
             fmt(std::max(0.5, xb - xa - 1)) + "\" height=\"" + fmt(std::abs(yb - yt)) + "\" fill=\"" + it.color + "\"/>\n";
      }
    }
  }
  s += "</g>\n";
  double ly = mt + 14;
  for (const auto& it : items_) {
    if (it.label.empty()) continue;
    s += "<rect x=\"" + fmt(ml + pw - 170) + "\" y=\"" + fmt(ly - 9) + "\" width=\"12\" height=\"10\" fill=\"" + it.color +
         "\"/><text x=\"" + fmt(ml + pw - 153) + "\" y=\"" + fmt(ly) + "\">" + html_escape(it.label) + "</text>\n";
    ly += 16;
  }
  s += "</svg>\n";
  return s;
}

}  // namespace sextant::replay
