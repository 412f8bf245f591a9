#pragma once
// What the S-D Lagrangian relaxation's bound proves at fixed multipliers u (relaxation_problem.hpp), beyond its
// value:
//  - RelaxationBound: the bound on the sub-problem a branch and bound node leaves (some detections covered, some
//    tuples blocked), over a subset of the tuples.  The relaxed sensors' uncovered detections each add min(0, u),
//    the (1, 2) pairs are a 2-D assignment over the available tuples' least reduced costs, tuples missing both
//    sensors 1 and 2 take every negative reduced cost.  Valid for any u; at the relaxation's best u it is close to
//    the packing LP's optimum, far tighter than the per-detection bound of packing_branch_and_bound.hpp (which
//    relaxes sensors 1 and 2 too).
//  - Reduced-cost fixing (the LP argument of Nemhauser & Wolsey, Integer and Combinatorial Optimization, II.2.2,
//    applied to the Lagrangian problem): with the 2-D assignment's optimal dual (alpha_a, beta_b;
//    assignment_with_missed.hpp), any solution that uses tuple t = (a, b, ...) costs at least
//        L(u) + increase_t,   increase_t = r_t - alpha_a - beta_b   (alpha_0 = beta_0 = 0; max(0, r_t) when a = b = 0),
//    r_t the reduced cost (forcing pairing (a, b), or row a unpaired with t's cost, raises the 2-D optimum by at
//    least that; the relaxed sensors' terms can only rise).  A tuple with L(u) + increase_t above the incumbent's
//    cost is in no better solution and is dropped.  Near the dual optimum most tuples go: on the 3 x 20 grid
//    scans with 5 false alarms (about 1000 tuples), a few dozen to a few hundred remain.
//  - solve_on_survivors: the exact branch and bound (packing_branch_and_bound.hpp) over the remaining tuples,
//    bounded by RelaxationBound on them, with the same fixing at every node.  Its optimum is the component's.
#include "assoc/assignment_with_missed.hpp"
#include "assoc/relaxation_problem.hpp"

#include <vector>

namespace sextant::assoc {

/// The relaxed problem's solution at one u, what reduced-cost fixing needs: each tuple's reduced cost, the 2-D
/// assignment's dual and the bound L(u).
struct RelaxedDual {
  std::vector<double> reduced;                // per tuple of P
  std::vector<double> row_dual, column_dual;  // of sensor 1's / sensor 2's detections (0-based)
  double bound = 0;                           // L(u)
};

/// The lower bound on the cost of any solution using tuple t of group g, above dual.bound.
double forcing_increase(const RelaxationProblem::PairGroup& g, double reduced, const std::vector<double>& row_dual,
                        const std::vector<double>& column_dual);

/// Positions (ascending) of the tuples of P (grouped as P.pair_groups()) that can be in a solution of cost at most
/// `upper` (up to 1e-9 relative), dual.bound + increase_t <= upper, and those of `incumbent` (a solution of cost
/// `upper`, kept whatever the rounding).
std::vector<int> reduced_cost_survivors(const std::vector<RelaxationProblem::PairGroup>& groups,
                                        const RelaxedDual& dual, double upper, const std::vector<int>& incumbent);

class RelaxationBound {
 public:
  /// Over the tuples `subset` of P (ascending positions; empty: all), at multipliers u (kept by reference).
  RelaxationBound(const RelaxationProblem& P, const Multipliers& u, std::vector<int> subset = {});

  /// `covered`: per detection of P.packing; `blocked`: per tuple of the subset (0: available).  `increase`, when
  /// not null: per tuple of the subset, forcing_increase at this node (0 for blocked ones).
  double operator()(const std::vector<char>& covered, const std::vector<int>& blocked,
                    std::vector<double>* increase = nullptr);

 private:
  const RelaxationProblem& P_;
  const Multipliers& u_;
  std::vector<int> subset_;
  std::vector<double> reduced_;                       // per subset tuple
  std::vector<RelaxationProblem::PairGroup> groups_;  // lo, hi: subset positions
  std::vector<double> row_missed_, column_missed_;
  std::vector<PairCost> pairs_;
  MissedAssignmentSolver solver_;
};

struct SurvivorSolution {
  std::vector<int> chosen;  // positions in P, sorted
  double cost = 0;
  double lower_bound = 0;  // the optimum when proven, else a valid bound
  long nodes = 0;
  bool proven = false;
};

/// The optimum over `survivors` (ascending positions in P, as reduced_cost_survivors gives at multipliers u, and
/// holding every tuple of `incumbent`, a feasible solution) by branch and bound within `max_nodes`.  When proven it
/// is the optimum of all of P (the other tuples are in no solution better than the incumbent).
SurvivorSolution solve_on_survivors(const RelaxationProblem& P, const Multipliers& u, const std::vector<int>& survivors,
                                    const std::vector<int>& incumbent, long max_nodes);

}  // namespace sextant::assoc
