#include "assoc/assignment_with_missed.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

namespace sextant::assoc {

MissedAssignment assign_with_missed(const std::vector<double>& row_missed, const std::vector<double>& column_missed,
                                    const std::vector<PairCost>& pairs) {
  return MissedAssignmentSolver().solve(row_missed, column_missed, pairs);
}

const MissedAssignment& MissedAssignmentSolver::solve(const std::vector<double>& row_missed,
                                                      const std::vector<double>& column_missed,
                                                      const std::vector<PairCost>& pairs) {
  const int R = static_cast<int>(row_missed.size()), C = static_cast<int>(column_missed.size());
  MissedAssignment& out = out_;
  out.value = 0;
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
  // Improving pairings, as gains w = cost - missed(row) - missed(column) < 0, by row (CSR), a duplicate (row,
  // column) keeping its smallest gain.
  auto& gains = gains_;
  gains.clear();
  for (const auto& p : pairs) {
    if (p.row < 0 || p.row >= R || p.column < 0 || p.column >= C)
      throw std::invalid_argument("assign_with_missed: pair (" + std::to_string(p.row) + ", " + std::to_string(p.column) +
                                  ") outside " + std::to_string(R) + " x " + std::to_string(C));
    if (!std::isfinite(p.cost)) throw std::invalid_argument("assign_with_missed: non-finite pair cost");
    const double w = p.cost - row_missed[static_cast<size_t>(p.row)] - column_missed[static_cast<size_t>(p.column)];
    if (w < 0) gains.push_back({p.row, p.column, w});
  }
  // The duals start at the unpaired costs (right for rows and columns no improving pairing touches).
  out.row_dual = row_missed, out.column_dual = column_missed;
  if (gains.empty()) return out;
  const auto by_row = [](const PairCost& a, const PairCost& b) {
    return a.row != b.row ? a.row < b.row : a.column != b.column ? a.column < b.column : a.cost < b.cost;
  };
  // The S-D solvers list their pairs row by row with ascending columns already (their tuples are sorted): a linear
  // check spares them the sort (about 2 % of the coplanar grid's instructions).
  if (!std::is_sorted(gains.begin(), gains.end(), by_row)) std::sort(gains.begin(), gains.end(), by_row);
  auto &begin = begin_, &column = column_;
  auto& gain = gain_;
  begin.assign(static_cast<size_t>(R) + 1, 0), column.clear(), gain.clear();
  for (size_t e = 0; e < gains.size(); ++e) {
    if (e > 0 && gains[e].row == gains[e - 1].row && gains[e].column == gains[e - 1].column) continue;
    ++begin[static_cast<size_t>(gains[e].row) + 1];
    column.push_back(gains[e].column);
    gain.push_back(gains[e].cost);
  }
  for (int r = 0; r < R; ++r) begin[static_cast<size_t>(r) + 1] += begin[static_cast<size_t>(r)];
  // Successive shortest augmenting paths (Dijkstra on reduced costs c - u_row - v_column >= 0, kept so by the
  // potential update), one row at a time.  Column nodes: 0..C-1 the real columns, C + r row r's own "unpaired"
  // slot (gain 0, adjacent to row r only), so every search ends at the latest at the row's own slot.  Only the
  // rows and columns a search reaches are touched: sparse scans cost about their edges, not rows x columns.
  const int N = C + R;
  auto &u = u_, &v = v_, &d = d_;
  auto &row_of = row_of_, &column_of = column_of_, &way = way_, &seen = seen_, &scanned = scanned_;
  auto& final = final_;
  u.assign(static_cast<size_t>(R), 0.0), v.assign(static_cast<size_t>(N), 0.0), d.assign(static_cast<size_t>(N), 0.0);
  row_of.assign(static_cast<size_t>(N), -1), column_of.assign(static_cast<size_t>(R), -1), way.assign(static_cast<size_t>(N), -1);
  seen.assign(static_cast<size_t>(N), -1);  // the search (row) that last reached the column
  final.assign(static_cast<size_t>(N), 0);
  auto& frontier = frontier_;  // the columns the search reached and has not finalized
  for (int r = 0; r < R; ++r) {
    const int b = begin[static_cast<size_t>(r)], e = begin[static_cast<size_t>(r) + 1];
    if (b == e) continue;  // no improving pairing: stays unpaired
    auto relax = [&](int i, int j, double w, double base) {
      const double nd = base + w - u[static_cast<size_t>(i)] - v[static_cast<size_t>(j)];
      bool seen_now = false;
      if (seen[static_cast<size_t>(j)] != r) seen[static_cast<size_t>(j)] = r, final[static_cast<size_t>(j)] = 0, seen_now = true;
      else if (final[static_cast<size_t>(j)] || !(nd < d[static_cast<size_t>(j)])) return;
      if (seen_now) frontier.push_back(j);
      d[static_cast<size_t>(j)] = nd, way[static_cast<size_t>(j)] = i;
    };
    double ur = -v[static_cast<size_t>(C + r)];
    for (int k = b; k < e; ++k) ur = std::min(ur, gain[static_cast<size_t>(k)] - v[static_cast<size_t>(column[static_cast<size_t>(k)])]);
    u[static_cast<size_t>(r)] = ur;
    scanned.clear();
    frontier.clear();
    relax(r, C + r, 0.0, 0.0);
    for (int k = b; k < e; ++k) relax(r, column[static_cast<size_t>(k)], gain[static_cast<size_t>(k)], 0.0);
    int end = -1;
    double delta = 0;
    while (!frontier.empty()) {
      size_t at = 0;
      for (size_t f = 1; f < frontier.size(); ++f)
        if (d[static_cast<size_t>(frontier[f])] < d[static_cast<size_t>(frontier[at])]) at = f;
      const int j = frontier[at];
      const double dj = d[static_cast<size_t>(j)];
      frontier[at] = frontier.back(), frontier.pop_back();
      final[static_cast<size_t>(j)] = 1;
      const int i = row_of[static_cast<size_t>(j)];
      if (i < 0) {
        end = j, delta = dj;
        break;
      }
      scanned.push_back(j);
      relax(i, C + i, 0.0, dj);
      for (int k = begin[static_cast<size_t>(i)]; k < begin[static_cast<size_t>(i) + 1]; ++k)
        relax(i, column[static_cast<size_t>(k)], gain[static_cast<size_t>(k)], dj);
    }
    // Potentials: rows on the search tree and the columns finalized before the end move by (delta - distance).
    u[static_cast<size_t>(r)] += delta;
    for (int j : scanned) {
      const double t = delta - d[static_cast<size_t>(j)];
      v[static_cast<size_t>(j)] -= t;
      u[static_cast<size_t>(row_of[static_cast<size_t>(j)])] += t;
    }
    for (int j = end;;) {  // augment along the path back to r
      const int i = way[static_cast<size_t>(j)];
      const int previous = column_of[static_cast<size_t>(i)];
      column_of[static_cast<size_t>(i)] = j, row_of[static_cast<size_t>(j)] = i;
      if (i == r) break;
      j = previous;
    }
  }
  for (int r = 0; r < R; ++r) {
    const int k = column_of[static_cast<size_t>(r)];
    if (k < 0 || k >= C) continue;  // unpaired (its own slot)
    double w = 0;
    for (int e = begin[static_cast<size_t>(r)]; e < begin[static_cast<size_t>(r) + 1]; ++e)
      if (column[static_cast<size_t>(e)] == k) w = gain[static_cast<size_t>(e)];
    out.column_of_row[static_cast<size_t>(r)] = k;
    out.row_of_column[static_cast<size_t>(k)] = r;
    out.value += w;
  }
  // The duals of the gains problem, mapped back: for the gains w = cost - missed(r) - missed(k) the potentials
  // satisfy u_r + v_k <= w (equality on matched pairs), u_r + v_{C+r} <= 0 (the row's own slot) and v_k <= 0
  // (v stays 0 on columns no search matched, so on every free column).  row_dual = missed(r) + u_r + v_{C+r}
  // and column_dual = missed(k) + v_k are then feasible for the original problem, and their sum equals `value`
  // by complementary slackness (a row's slot column is matched to it or untouched).
  for (int r = 0; r < R; ++r) out.row_dual[static_cast<size_t>(r)] += u[static_cast<size_t>(r)] + v[static_cast<size_t>(C + r)];
  for (int k = 0; k < C; ++k) out.column_dual[static_cast<size_t>(k)] += v[static_cast<size_t>(k)];
  return out;
}

}  // namespace sextant::assoc
