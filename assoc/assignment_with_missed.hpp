#pragma once
// The 2-D assignment in which any row or column may stay unpaired (the building block of the S-D Lagrangian
// relaxation, Pattipati et al., IEEE TAC 37(2) 1992): rows r and columns k, a sparse list of allowed pairings with
// their costs, and the cost of leaving each row or column unpaired.  Minimizes the total cost.
//
// A pairing that does not beat leaving both unpaired (cost(r, k) >= missed(r) + missed(k)) is never needed, so
// only the improving pairings are kept, as gains; the rest is a maximum-gain bipartite matching, solved by
// successive shortest augmenting paths (Dijkstra with dual potentials, one row at a time; each row has a private
// zero-gain "unpaired" slot, so every search ends).  A search only touches what it reaches: sparse scans (gated
// tuples) cost about their number of pairings times the frontier, not rows x columns.  The frontier is scanned
// linearly for its nearest column rather than kept in a heap: the searches of the S-D relaxation reach a few
// columns each (about 1.5 finalized per row on the 3 x 20 grid scans), and the heap's pushes cost more than the
// scans (the relaxation 16 % faster there).
#include <vector>

namespace sextant::assoc {

struct PairCost {
  int row = 0, column = 0;  // 0-based
  double cost = 0;          // finite; a duplicate (row, column) keeps the smaller cost
};

struct MissedAssignment {
  std::vector<int> column_of_row;  // -1: the row stays unpaired
  std::vector<int> row_of_column;  // -1: the column stays unpaired
  double value = 0;                // summed cost of the pairs and of the unpaired rows and columns
  // An optimal LP dual, the certificate of `value`: row_dual[r] + column_dual[k] <= cost(r, k) for every pairing,
  // row_dual[r] <= row_missed[r], column_dual[k] <= column_missed[k], and the duals sum to `value`.  So forcing
  // pairing (r, k) costs at least cost(r, k) - row_dual[r] - column_dual[k] more than `value`, and leaving row r
  // unpaired at cost c instead of row_missed[r] at least c - row_dual[r] more (what the S-D relaxation's
  // reduced-cost fixing uses, relaxation_bound.hpp).
  std::vector<double> row_dual, column_dual;
};

/// `row_missed[r]`, `column_missed[k]`: finite costs of leaving row r / column k unpaired.  Throws
/// std::invalid_argument on an out-of-range index or a non-finite cost.
MissedAssignment assign_with_missed(const std::vector<double>& row_missed, const std::vector<double>& column_missed,
                                    const std::vector<PairCost>& pairs);

/// The same solver keeping its working memory between calls (no allocation once its buffers have grown to the
/// problem size), for callers that solve many such problems in a loop (the Lagrangian relaxation).  The returned
/// reference stays valid until the next call.
class MissedAssignmentSolver {
 public:
  const MissedAssignment& solve(const std::vector<double>& row_missed, const std::vector<double>& column_missed,
                                const std::vector<PairCost>& pairs);

 private:
  // solve's steps.
  void start_unpaired(const std::vector<double>& row_missed, const std::vector<double>& column_missed);
  void collect_gains(const std::vector<double>& row_missed, const std::vector<double>& column_missed,
                     const std::vector<PairCost>& pairs);
  void index_gains_by_row();
  void augment_from_row(int r);
  void relax(int search, int i, int j, double w, double base);
  void read_matching();
  void map_duals();

  int R_ = 0, C_ = 0;  // rows, columns
  MissedAssignment out_;
  std::vector<PairCost> gains_;
  std::vector<int> begin_, column_, row_of_, column_of_, way_, seen_, scanned_;
  std::vector<double> gain_, u_, v_, d_;
  std::vector<char> final_;
  std::vector<int> frontier_;
};

}  // namespace sextant::assoc
