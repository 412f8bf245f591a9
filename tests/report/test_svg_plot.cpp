// The report's SVG plots: framing that a far outlier cannot squeeze, lines coloured by a value on the viridis scale,
// named bars, statistic lines, reproducible markup.
#include "report/svg_plot.hpp"

#include <doctest/doctest.h>

#include <regex>
#include <set>

using namespace sextant::tools;

namespace {
size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}
}  // namespace

TEST_CASE("robust_view: the truth and the bulk of the estimates, not a far ghost") {
  // Four targets in a 60 m x 40 m region, 80 estimates around them, one ghost 230 m away.
  const std::vector<Eigen::Vector2d> truth = {{-20, -10}, {25, -15}, {10, 18}, {-28, 15}};
  std::vector<Eigen::Vector2d> est;
  for (int k = 0; k < 80; ++k) est.push_back(truth[k % 4] + Eigen::Vector2d(0.1 * (k % 7) - 0.3, 0.1 * (k % 5) - 0.2));
  est.emplace_back(230, 4);
  const Eigen::Vector4d v = robust_view(truth, est, 0.05, 0.15, 2.0);
  for (const auto& t : truth) CHECK((t.x() > v[0] && t.x() < v[1] && t.y() > v[2] && t.y() < v[3]));
  CHECK(v[1] < 40);         // the ghost is outside the frame...
  CHECK(v[1] - v[0] < 80);  // ...and the frame is about the region (53 m wide) plus its margins
  // Between the truth's extent (x in [-28, 25]) and the estimates' ([-28.3, 25.3]), widened by 15 % on each side.
  CHECK(v[0] <= -28 - 0.15 * 53 + 1e-9);
  CHECK(v[0] >= -28.3 - 0.15 * 53.6 - 1e-9);
  CHECK(v[1] >= 25 + 0.15 * 53 - 1e-9);
  CHECK(v[1] <= 25.3 + 0.15 * 53.6 + 1e-9);
  // Without the tail, the ghost is framed in.
  CHECK(robust_view(truth, est, 0.0)[1] > 230);
  // Few points: nothing is dropped, and a single point gets the minimum margin.
  const Eigen::Vector4d one = robust_view({}, {{5, 5}}, 0.05, 0.15, 2.0);
  CHECK(one == Eigen::Vector4d(3, 7, 3, 7));
  CHECK(robust_view({}, {}) == Eigen::Vector4d(0, 1, 0, 1));
}

TEST_CASE("a view clips the plot to the frame") {
  SvgPlot p("Targets", "x", "y");
  p.points({{0, 0}, {1, 1}, {230, 0}}, "#d62728", "targets");
  p.set_view(-2, 3, -2, 3);
  const std::string s = p.render();
  CHECK(count(s, "<clipPath") == 1);
  CHECK(count(s, "clip-path=\"url(#") == 1);
  // The tick labels are those of the frame (-2..3), not of the ghost's 0..230.
  CHECK(s.find(">200<") == std::string::npos);
  CHECK(s.find(">2<") != std::string::npos);
}

TEST_CASE("a line coloured by its values: viridis from the minimum to the maximum, with a colour bar") {
  CHECK(viridis(0) == "#440154");
  CHECK(viridis(1) == "#fde725");
  CHECK(viridis(-3) == viridis(0));
  CHECK(viridis(0.5) == "#21908d");
  SvgPlot p("Trajectory", "x", "y");
  std::vector<Eigen::Vector2d> pts;
  std::vector<double> err;
  for (int k = 0; k <= 100; ++k) pts.emplace_back(k, 0), err.push_back(k < 50 ? 0.01 : 0.5);  // two levels
  p.colored_polyline(pts, err, "ATE [m]");
  const std::string s = p.render();
  const std::regex colored("stroke=\"(#[0-9a-f]{6})\"[^>]*class=\"series colored\"");
  std::set<std::string> colours;
  size_t runs = 0;
  for (auto it = std::sregex_iterator(s.begin(), s.end(), colored); it != std::sregex_iterator(); ++it, ++runs)
    colours.insert((*it)[1]);
  // 0.01 everywhere, then one segment halfway (mean 0.255), then 0.5: three runs, the ends at the scale's ends.
  CHECK(runs == 3);
  CHECK(colours.count(viridis(0.5 / 64)) == 1);
  CHECK(colours.count(viridis(63.5 / 64)) == 1);
  CHECK(count(s, "class=\"colorbar\"") == 1);
  CHECK(s.find("ATE [m]") != std::string::npos);
  CHECK(s.find(">0.5<") != std::string::npos);  // the bar's maximum
}

TEST_CASE("named bars, statistic lines and bands, and the same calls give the same markup") {
  auto make = [] {
    SvgPlot p("Messages", "", "messages");
    p.histogram({0, 1, 2, 3}, {160, 200, 1001}, "#1f77b4", "received");
    p.set_x_categories({"BEARINGS", "LANDMARKS", "ODOMETRY"});
    p.hline(500, "#000000", "rmse 500");
    p.hband(100, 300, "#bcbd22", "mean \u00b1 std");
    return p.render();
  };
  const std::string s = make();
  CHECK(count(s, "class=\"category\"") == 3);
  CHECK(s.find(">ODOMETRY</text>") != std::string::npos);
  CHECK(count(s, "class=\"stat\"") == 2);
  CHECK(s.find("stroke-dasharray") != std::string::npos);
  CHECK(s.find(">rmse 500</text>") != std::string::npos);
  CHECK(make() == s);
}
