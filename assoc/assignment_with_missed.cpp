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
  R_ = static_cast<int>(row_missed.size()), C_ = static_cast<int>(column_missed.size());
  start_unpaired(row_missed, column_missed);
  collect_gains(row_missed, column_missed, pairs);
  // The duals start at the unpaired costs (right for rows and columns no improving pairing touches).
  out_.row_dual = row_missed, out_.column_dual = column_missed;
  if (gains_.empty()) return out_;
  index_gains_by_row();
  // Successive shortest augmenting paths (Dijkstra on reduced costs c - u_row - v_column >= 0, kept so by the
  // potential update), one row at a time.  Column nodes: 0..C-1 the real columns, C + r row r's own "unpaired"
  // slot (gain 0, adjacent to row r only), so every search ends at the latest at the row's own slot.  Only the
  // rows and columns a search reaches are touched: sparse scans cost about their edges, not rows x columns.
  const auto N = static_cast<size_t>(C_ + R_);
  u_.assign(static_cast<size_t>(R_), 0.0), v_.assign(N, 0.0), d_.assign(N, 0.0);
  row_of_.assign(N, -1), column_of_.assign(static_cast<size_t>(R_), -1), way_.assign(N, -1);
  seen_.assign(N, -1);  // the search (row) that last reached the column
  final_.assign(N, 0);
  for (int r = 0; r < R_; ++r)
    if (begin_[static_cast<size_t>(r)] != begin_[static_cast<size_t>(r) + 1])
      augment_from_row(r);  // else: no improving pairing, stays unpaired
  read_matching();
  map_duals();
  return out_;
}

// Every row and column unpaired: `value` their summed costs (which must be finite).
void MissedAssignmentSolver::start_unpaired(const std::vector<double>& row_missed,
                                            const std::vector<double>& column_missed) {
  out_.value = 0;
  out_.column_of_row.assign(static_cast<size_t>(R_), -1);
  out_.row_of_column.assign(static_cast<size_t>(C_), -1);
  for (double m : row_missed) {
    if (!std::isfinite(m)) throw std::invalid_argument("assign_with_missed: non-finite cost of an unpaired row");
    out_.value += m;
  }
  for (double m : column_missed) {
    if (!std::isfinite(m)) throw std::invalid_argument("assign_with_missed: non-finite cost of an unpaired column");
    out_.value += m;
  }
}

// Improving pairings, as gains w = cost - missed(row) - missed(column) < 0.
void MissedAssignmentSolver::collect_gains(const std::vector<double>& row_missed,
                                           const std::vector<double>& column_missed,
                                           const std::vector<PairCost>& pairs) {
  gains_.clear();
  for (const auto& p : pairs) {
    if (p.row < 0 || p.row >= R_ || p.column < 0 || p.column >= C_)
      throw std::invalid_argument("assign_with_missed: pair (" + std::to_string(p.row) + ", " +
                                  std::to_string(p.column) + ") outside " + std::to_string(R_) + " x " +
                                  std::to_string(C_));
    if (!std::isfinite(p.cost)) throw std::invalid_argument("assign_with_missed: non-finite pair cost");
    const double w = p.cost - row_missed[static_cast<size_t>(p.row)] - column_missed[static_cast<size_t>(p.column)];
    if (w < 0) gains_.push_back({p.row, p.column, w});
  }
}

// The gains by row (CSR: begin_, column_, gain_), a duplicate (row, column) keeping its smallest gain.
void MissedAssignmentSolver::index_gains_by_row() {
  const auto by_row = [](const PairCost& a, const PairCost& b) {
    return a.row != b.row ? a.row < b.row : a.column != b.column ? a.column < b.column : a.cost < b.cost;
  };
  // The S-D solvers list their pairs row by row with ascending columns already (their tuples are sorted): a linear
  // check spares them the sort (about 2 % of the coplanar grid's instructions).
  if (!std::is_sorted(gains_.begin(), gains_.end(), by_row)) std::sort(gains_.begin(), gains_.end(), by_row);
  begin_.assign(static_cast<size_t>(R_) + 1, 0), column_.clear(), gain_.clear();
  for (size_t e = 0; e < gains_.size(); ++e) {
    if (e > 0 && gains_[e].row == gains_[e - 1].row && gains_[e].column == gains_[e - 1].column) continue;
    ++begin_[static_cast<size_t>(gains_[e].row) + 1];
    column_.push_back(gains_[e].column);
    gain_.push_back(gains_[e].cost);
  }
  for (int r = 0; r < R_; ++r) begin_[static_cast<size_t>(r) + 1] += begin_[static_cast<size_t>(r)];
}

// Search `search` reaches column j from row i over an edge of gain w at distance `base` of row i.
void MissedAssignmentSolver::relax(int search, int i, int j, double w, double base) {
  const double nd = base + w - u_[static_cast<size_t>(i)] - v_[static_cast<size_t>(j)];
  bool seen_now = false;
  if (seen_[static_cast<size_t>(j)] != search)
    seen_[static_cast<size_t>(j)] = search, final_[static_cast<size_t>(j)] = 0, seen_now = true;
  else if (final_[static_cast<size_t>(j)] || !(nd < d_[static_cast<size_t>(j)]))
    return;
  if (seen_now) frontier_.push_back(j);
  d_[static_cast<size_t>(j)] = nd, way_[static_cast<size_t>(j)] = i;
}

// One row's shortest augmenting path: Dijkstra from row r (the frontier scanned linearly for its nearest column)
// to the first free column, the potentials updated, the matching augmented along the path.
void MissedAssignmentSolver::augment_from_row(int r) {
  const int C = C_, b = begin_[static_cast<size_t>(r)], e = begin_[static_cast<size_t>(r) + 1];
  double ur = -v_[static_cast<size_t>(C + r)];
  for (int k = b; k < e; ++k)
    ur = std::min(ur, gain_[static_cast<size_t>(k)] - v_[static_cast<size_t>(column_[static_cast<size_t>(k)])]);
  u_[static_cast<size_t>(r)] = ur;
  scanned_.clear();
  frontier_.clear();
  relax(r, r, C + r, 0.0, 0.0);
  for (int k = b; k < e; ++k) relax(r, r, column_[static_cast<size_t>(k)], gain_[static_cast<size_t>(k)], 0.0);
  int end = -1;
  double delta = 0;
  while (!frontier_.empty()) {
    size_t at = 0;
    for (size_t f = 1; f < frontier_.size(); ++f)
      if (d_[static_cast<size_t>(frontier_[f])] < d_[static_cast<size_t>(frontier_[at])]) at = f;
    const int j = frontier_[at];
    const double dj = d_[static_cast<size_t>(j)];
    frontier_[at] = frontier_.back(), frontier_.pop_back();
    final_[static_cast<size_t>(j)] = 1;
    const int i = row_of_[static_cast<size_t>(j)];
    if (i < 0) {
      end = j, delta = dj;
      break;
    }
    scanned_.push_back(j);
    relax(r, i, C + i, 0.0, dj);
    for (int k = begin_[static_cast<size_t>(i)]; k < begin_[static_cast<size_t>(i) + 1]; ++k)
      relax(r, i, column_[static_cast<size_t>(k)], gain_[static_cast<size_t>(k)], dj);
  }
  // Potentials: rows on the search tree and the columns finalized before the end move by (delta - distance).
  u_[static_cast<size_t>(r)] += delta;
  for (int j : scanned_) {
    const double t = delta - d_[static_cast<size_t>(j)];
    v_[static_cast<size_t>(j)] -= t;
    u_[static_cast<size_t>(row_of_[static_cast<size_t>(j)])] += t;
  }
  for (int j = end;;) {  // augment along the path back to r
    const int i = way_[static_cast<size_t>(j)];
    const int previous = column_of_[static_cast<size_t>(i)];
    column_of_[static_cast<size_t>(i)] = j, row_of_[static_cast<size_t>(j)] = i;
    if (i == r) break;
    j = previous;
  }
}

// The matched pairs into the result, their gains added to `value`.
void MissedAssignmentSolver::read_matching() {
  for (int r = 0; r < R_; ++r) {
    const int k = column_of_[static_cast<size_t>(r)];
    if (k < 0 || k >= C_) continue;  // unpaired (its own slot)
    double w = 0;
    for (int e = begin_[static_cast<size_t>(r)]; e < begin_[static_cast<size_t>(r) + 1]; ++e)
      if (column_[static_cast<size_t>(e)] == k) w = gain_[static_cast<size_t>(e)];
    out_.column_of_row[static_cast<size_t>(r)] = k;
    out_.row_of_column[static_cast<size_t>(k)] = r;
    out_.value += w;
  }
}

// The duals of the gains problem, mapped back: for the gains w = cost - missed(r) - missed(k) the potentials
// satisfy u_r + v_k <= w (equality on matched pairs), u_r + v_{C+r} <= 0 (the row's own slot) and v_k <= 0 (v stays
// 0 on columns no search matched, so on every free column).  row_dual = missed(r) + u_r + v_{C+r} and
// column_dual = missed(k) + v_k are then feasible for the original problem, and their sum equals `value` by
// complementary slackness (a row's slot column is matched to it or untouched).
void MissedAssignmentSolver::map_duals() {
  for (int r = 0; r < R_; ++r)
    out_.row_dual[static_cast<size_t>(r)] += u_[static_cast<size_t>(r)] + v_[static_cast<size_t>(C_ + r)];
  for (int k = 0; k < C_; ++k) out_.column_dual[static_cast<size_t>(k)] += v_[static_cast<size_t>(k)];
}

}  // namespace sextant::assoc
