#pragma once
// A minimal SVG plot: data coordinates mapped into a fixed-size panel with axes, ticks and a legend; polylines,
// points, covariance ellipses and histogram bars.  Self-contained markup for the HTML report (no scripts).
#include <Eigen/Core>

#include <string>
#include <vector>

namespace sextant::replay {

class SvgPlot {
 public:
  SvgPlot(std::string title, std::string x_label, std::string y_label, int width = 640, int height = 420);

  /// Keep x and y on the same scale (maps, top views).
  void set_equal_aspect(bool equal) { equal_aspect_ = equal; }
  void polyline(const std::vector<Eigen::Vector2d>& points, const std::string& color, const std::string& label,
                double stroke_width = 1.5);
  void points(const std::vector<Eigen::Vector2d>& points, const std::string& color, const std::string& label,
              double radius = 2.5);
  /// The 1-sigma... k-sigma ellipse of a 2x2 covariance around `centre`.
  void ellipse(const Eigen::Vector2d& centre, const Eigen::Matrix2d& covariance, double k_sigma, const std::string& color);
  /// Bars of a histogram: edges (n+1 values) and counts (n values).
  void histogram(const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color,
                 const std::string& label);

  /// The <svg> element.
  std::string render() const;
  bool empty() const { return items_.empty(); }

 private:
  struct Item {
    enum Kind { kLine, kPoints, kEllipse, kBars } kind;
    std::vector<Eigen::Vector2d> pts;  // for ellipses: the sampled outline
    std::string color, label;
    double size = 1.5;
  };
  std::string title_, x_label_, y_label_;
  int width_, height_;
  bool equal_aspect_ = false;
  std::vector<Item> items_;
};

/// Escapes text for HTML/SVG.
std::string html_escape(const std::string& s);

}  // namespace sextant::replay
