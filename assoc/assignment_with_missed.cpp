#include "assoc/assignment_with_missed.hpp"

#include "assoc/assignment_2d.hpp"

#include <Eigen/Core>

#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace sextant::assoc {
namespace {

int find_root(std::vector<int>& parent, int x) {
  while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
  return x;
}

}  // namespace

MissedAssignment assign_with_missed(const std::vector<double>& row_missed, const std::vector<double>& column_missed,
                                    const std::vector<PairCost>& pairs) {
  const int R = static_cast<int>(row_missed.size()), C = static_cast<int>(column_missed.size());
  MissedAssignment out;
  out.column_of_row.assign(static_cast<size_t>(R), -1);
  out.row_of_column.assign(static_cast<size_t>(C), -1);
  for (double m : row_missed) {
    if (!std::isfinite(m)) throw std::invalid_argument("assign_with_missed: non-finite cost of an unpaired row");
    out.value += m;
  }
  for (double m : column_missed) {
    if (!std::isfinite(m)) throw std::invalid_argument("assign_with_missed: non-finite cost of an unpaired column");
    out.value += m;
  }
  // Improving pairings, as gains w = cost - missed(row) - missed(column) < 0; nodes 0..R-1 rows, R..R+C-1 columns.
  std::vector<int> parent(static_cast<size_t>(R + C));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<PairCost> gains;
  for (const auto& p : pairs) {
    if (p.row < 0 || p.row >= R || p.column < 0 || p.column >= C)
      throw std::invalid_argument("assign_with_missed: pair (" + std::to_string(p.row) + ", " + std::to_string(p.column) +
                                  ") outside " + std::to_string(R) + " x " + std::to_string(C));
    if (!std::isfinite(p.cost)) throw std::invalid_argument("assign_with_missed: non-finite pair cost");
    const double w = p.cost - row_missed[static_cast<size_t>(p.row)] - column_missed[static_cast<size_t>(p.column)];
    if (!(w < 0)) continue;
    gains.push_back({p.row, p.column, w});
    parent[static_cast<size_t>(find_root(parent, p.row))] = find_root(parent, R + p.column);
  }
  if (gains.empty()) return out;
  // Components: local numbering of their rows and columns.
  std::vector<int> component(static_cast<size_t>(R + C), -1), local(static_cast<size_t>(R + C), -1);
  std::vector<std::vector<int>> rows, columns;
  std::vector<std::vector<PairCost>> edges;
  auto component_of = [&](int node) {
    const int root = find_root(parent, node);
    if (component[static_cast<size_t>(root)] < 0) {
      component[static_cast<size_t>(root)] = static_cast<int>(rows.size());
      rows.emplace_back(), columns.emplace_back(), edges.emplace_back();
    }
    return component[static_cast<size_t>(root)];
  };
  for (const auto& g : gains) {
    const int c = component_of(g.row);
    if (local[static_cast<size_t>(g.row)] < 0) local[static_cast<size_t>(g.row)] = static_cast<int>(rows[static_cast<size_t>(c)].size()), rows[static_cast<size_t>(c)].push_back(g.row);
    const int col = R + g.column;
    if (local[static_cast<size_t>(col)] < 0) local[static_cast<size_t>(col)] = static_cast<int>(columns[static_cast<size_t>(c)].size()), columns[static_cast<size_t>(c)].push_back(g.column);
    edges[static_cast<size_t>(c)].push_back(g);
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (size_t c = 0; c < rows.size(); ++c) {
    const auto nr = static_cast<Eigen::Index>(rows[c].size()), nc = static_cast<Eigen::Index>(columns[c].size());
    // Rows x (columns, then one zero-gain "unpaired" slot per row): every row is assigned, columns may stay free.
    Eigen::MatrixXd m = Eigen::MatrixXd::Constant(nr, nc + nr, kInf);
    m.rightCols(nr).setZero();
    for (const auto& e : edges[c]) {
      double& x = m(local[static_cast<size_t>(e.row)], local[static_cast<size_t>(R + e.column)]);
      x = std::min(x, e.cost);
    }
    const auto a = solve_assignment_2d(m);  // always feasible: the unpaired slots
    for (Eigen::Index r = 0; r < nr; ++r) {
      const int k = a.column_of_row[static_cast<size_t>(r)];
      if (k < 0 || k >= nc) continue;
      const int row = rows[c][static_cast<size_t>(r)], column = columns[c][static_cast<size_t>(k)];
      out.column_of_row[static_cast<size_t>(row)] = column;
      out.row_of_column[static_cast<size_t>(column)] = row;
      out.value += m(r, k);
    }
  }
  return out;
}

}  // namespace sextant::assoc
