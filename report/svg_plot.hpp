#pragma once
// A minimal SVG plot: data coordinates mapped into a fixed-size panel with axes, ticks and a legend; polylines (plain
// or coloured by a value, with a colour bar), points, covariance ellipses, histogram bars with optional category
// names, horizontal statistic lines and bands; fitted to the data or framed to a given view (the rest clipped).
// Self-contained markup for the HTML report (no scripts); the output depends only on the calls, so reports are
// byte-identical from run to run.
#include <Eigen/Core>

#include <string>
#include <vector>

namespace sextant::tools {

class SvgPlot {
 public:
  SvgPlot(std::string title, std::string x_label, std::string y_label, int width = 640, int height = 420);

  /// A second, smaller title line (the parameters of an experiment).
  void set_subtitle(std::string subtitle) { subtitle_ = std::move(subtitle); }
  /// The legend in the bottom right corner instead of the top right (curves that rise to the right).
  void set_legend_bottom(bool bottom) { legend_bottom_ = bottom; }
  /// Keep x and y on the same scale (maps, top views).
  void set_equal_aspect(bool equal) { equal_aspect_ = equal; }
  void polyline(const std::vector<Eigen::Vector2d>& points, const std::string& color, const std::string& label,
                double stroke_width = 1.5);
  void points(const std::vector<Eigen::Vector2d>& points, const std::string& color, const std::string& label,
              double radius = 2.5);
  /// The 1-sigma... k-sigma ellipse of a 2x2 covariance around `centre`.
  void ellipse(const Eigen::Vector2d& centre, const Eigen::Matrix2d& covariance, double k_sigma,
               const std::string& color);
  /// Bars of a histogram: edges (n+1 values) and counts (n values).
  void histogram(const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color,
                 const std::string& label);
  /// A line whose segments take the colour of `values` (one per point) on the viridis scale from their minimum
  /// (dark blue) to their maximum (yellow); a colour bar labelled `value_label` shows the scale.
  void colored_polyline(const std::vector<Eigen::Vector2d>& points, const std::vector<double>& values,
                        const std::string& value_label, double stroke_width = 2.5);
  /// A horizontal line at y across the plot, dashed (a statistic such as the RMSE).
  void hline(double y, const std::string& color, const std::string& label);
  /// A translucent horizontal band from y_lo to y_hi across the plot (mean ± std).
  void hband(double y_lo, double y_hi, const std::string& color, const std::string& label);
  /// Names of the bars at x in [0, 1), [1, 2), ...: written under them instead of numeric x ticks.
  void set_x_categories(std::vector<std::string> names) { categories_ = std::move(names); }
  /// Frames the plot to this data rectangle instead of fitting every item; what lies outside is clipped.
  void set_view(double x0, double x1, double y0, double y1) {
    view_ = {x0, x1, y0, y1};
    has_view_ = true;
  }

  /// The <svg> element.
  std::string render() const;
  bool empty() const { return items_.empty(); }

 private:
  struct Item {
    enum Kind { kLine, kPoints, kEllipse, kBars, kColoredLine, kHLine, kBand } kind;
    std::vector<Eigen::Vector2d> pts;  // ellipses: the sampled outline; hline/band: (0, y) per y value
    std::string color, label;
    double size = 1.5;
    std::vector<double> values;  // coloured line: one per point
  };
  std::string title_, x_label_, y_label_, subtitle_;
  bool legend_bottom_ = false;
  int width_, height_;
  bool equal_aspect_ = false;
  bool has_view_ = false;
  Eigen::Vector4d view_ = Eigen::Vector4d::Zero();  // x0, x1, y0, y1
  std::vector<std::string> categories_;
  std::vector<Item> items_;

  // render's steps (svg_plot.cpp): the frame (margins, plot area, data range), then the parts drawn in it.
  struct Frame;
  Frame frame() const;
  void render_axes(std::string& s, const Frame& f) const;
  void render_items(std::string& s, const Frame& f) const;
  void render_colour_bar(std::string& s, const Frame& f) const;
  void render_legend(std::string& s, const Frame& f) const;
};

/// A view [x0, x1, y0, y1] that shows every point of `must_show` and the central part of `points` (per axis, between
/// their `tail` and 1 - `tail` quantiles), widened by `margin` of its size on each side (at least `min_margin`): a
/// plot framed this way is not squeezed into a corner by a few far outliers (a ghost target at 230 m).  An empty
/// input gives [0, 1, 0, 1].
Eigen::Vector4d robust_view(const std::vector<Eigen::Vector2d>& must_show, const std::vector<Eigen::Vector2d>& points,
                            double tail = 0.02, double margin = 0.15, double min_margin = 1.0);

/// The viridis colour of t in [0, 1] as "#rrggbb" (matplotlib's scale, linear between 9 of its stops).
std::string viridis(double t);

/// Escapes text for HTML/SVG.
std::string html_escape(const std::string& s);

}  // namespace sextant::tools
