#include "assoc/assignment_2d.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sextant::assoc {

Assignment2D solve_assignment_2d(const Eigen::MatrixXd& C) {
  const bool transposed = C.rows() > C.cols();
  Eigen::MatrixXd copy;  // only when transposed: the rows must be the shorter side
  if (transposed) copy = C.transpose();
  const Eigen::MatrixXd& a = transposed ? copy : C;
  const int n = static_cast<int>(a.rows()), m = static_cast<int>(a.cols());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Assignment2D out;
  // 1-indexed potentials; p[j] = row matched to column j (0 = none); way[] = the alternating path.
  std::vector<double> u(static_cast<size_t>(n) + 1, 0), v(static_cast<size_t>(m) + 1, 0);
  std::vector<int> p(static_cast<size_t>(m) + 1, 0), way(static_cast<size_t>(m) + 1, 0);
  std::vector<double> minv(static_cast<size_t>(m) + 1);
  std::vector<char> used(static_cast<size_t>(m) + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(minv.begin(), minv.end(), kInf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[static_cast<size_t>(j0)] = true;
      const int i0 = p[static_cast<size_t>(j0)];
      double delta = kInf;
      int j1 = -1;
      const double ui0 = u[static_cast<size_t>(i0)];
      for (int j = 1; j <= m; ++j) {
        if (used[static_cast<size_t>(j)]) continue;
        const double c = a(i0 - 1, j - 1);
        if (c < kInf && c > -kInf) {  // not finite (+infinity): forbidden
          const double cur = c - ui0 - v[static_cast<size_t>(j)];
          if (cur < minv[static_cast<size_t>(j)]) minv[static_cast<size_t>(j)] = cur, way[static_cast<size_t>(j)] = j0;
        }
        if (minv[static_cast<size_t>(j)] < delta) delta = minv[static_cast<size_t>(j)], j1 = j;
      }
      if (j1 < 0 || !std::isfinite(delta)) return out;  // row i cannot be augmented: infeasible
      for (int j = 0; j <= m; ++j) {
        if (used[static_cast<size_t>(j)]) {
          u[static_cast<size_t>(p[static_cast<size_t>(j)])] += delta;
          v[static_cast<size_t>(j)] -= delta;
        } else {
          minv[static_cast<size_t>(j)] -= delta;
        }
      }
      j0 = j1;
    } while (p[static_cast<size_t>(j0)] != 0);
    do {
      const int j1 = way[static_cast<size_t>(j0)];
      p[static_cast<size_t>(j0)] = p[static_cast<size_t>(j1)];
      j0 = j1;
    } while (j0);
  }
  std::vector<int> col(static_cast<size_t>(n), -1);
  for (int j = 1; j <= m; ++j)
    if (p[static_cast<size_t>(j)] > 0) col[static_cast<size_t>(p[static_cast<size_t>(j)] - 1)] = j - 1;
  out.feasible = true;
  if (!transposed) {
    out.column_of_row = col;
    for (int i = 0; i < n; ++i) out.cost += a(i, col[static_cast<size_t>(i)]);
    out.u.assign(u.begin() + 1, u.end());
    out.v.assign(v.begin() + 1, v.end());
  } else {
    out.column_of_row.assign(static_cast<size_t>(m), -1);
    for (int i = 0; i < n; ++i)
      out.column_of_row[static_cast<size_t>(col[static_cast<size_t>(i)])] = i,
      out.cost += a(i, col[static_cast<size_t>(i)]);
    out.u.assign(v.begin() + 1, v.end());
    out.v.assign(u.begin() + 1, u.end());
  }
  return out;
}

}  // namespace sextant::assoc
