#pragma once
// The 2-D (linear sum) assignment problem: given an n x m cost matrix, choose for each row a distinct column
// minimizing the summed cost; +infinity marks a forbidden pairing.  Rectangular matrices are fine (the shorter
// side is fully assigned).  Shortest augmenting paths with dual potentials (the Jonker-Volgenant / Hungarian
// family, O(n^2 m); Crouse, "On implementing 2D rectangular assignment algorithms", IEEE T-AES 52(4), 2016).
// Never hangs on an infeasible matrix: it says so.
#include <Eigen/Core>

#include <vector>

namespace sextant::assoc {

struct Assignment2D {
  bool feasible = false;
  std::vector<int> column_of_row;  // -1 for rows left unassigned (only when rows > columns)
  double cost = 0;
  // Dual potentials (row u, column v) with u_i + v_j <= c_ij, equality on assigned pairs: the optimality
  // certificate, and what Lagrangian relaxation reuses.
  std::vector<double> u, v;
};

Assignment2D solve_assignment_2d(const Eigen::MatrixXd& cost);

}  // namespace sextant::assoc
