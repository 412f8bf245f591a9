#pragma once
// Data association for landmark sightings with unknown ids.
//  - Individual compatibility: sighting i and landmark j pair when the innovation's Mahalanobis distance
//    D2_ij = nu' S^-1 nu, S = H_ij P H_ij' + R_i, is below a chi-square gate.
//  - Nearest neighbour: each sighting takes its individually compatible landmark of smallest D2 (landmarks used once).
//  - Joint compatibility branch and bound (Neira & Tardos, "Data association in stochastic mapping using the joint
//    compatibility test", IEEE T-RA 17(6), 2001): the hypothesis pairing the most sightings whose stacked innovation
//    passes the joint test D2_H = nu_H' (H_H P H_H' + R_H)^-1 nu_H < chi2(sum of dims), ties broken by smaller D2_H.
//    The joint test sees the correlations that a shared robot pose induces, which rejects the individually
//    plausible but jointly inconsistent pairings of a cluttered or repetitive map.
// The filter supplies, for each candidate pair, the innovation and the Jacobian row block over its state (dense, or
// only its non-zero columns); this library knows nothing of the state's layout.
//
// Bounded work: JCBB's search is exponential in the number of sightings and every joint test costs O(dim^3), so a
// batch of thousands of sightings would never end.  Every distance computed is charged to `work_budget` (in
// floating-point operations, roughly: d k^2 + d^2 k + d^3 for an innovation of dimension d over k state columns);
// when it runs out,
//   - during the individual tests: the sightings not yet fully examined are left unpaired and reported as not
//     examined (the caller must not treat them as new landmarks: nothing was learnt about them);
//   - during the search: the answer is nearest neighbour over the individually compatible pairs already computed
//     (sound, but blind to the correlations the joint test sees), and `exhausted` says so.
#include "assoc/chi_square.hpp"

#include <Eigen/Core>

#include <functional>
#include <optional>
#include <vector>

namespace sextant::assoc {

/// The linearized prediction of sighting i as landmark j: innovation nu = z_i - h_j(x), Jacobian H (d x n).
struct Candidate {
  Eigen::VectorXd innovation;
  Eigen::MatrixXd jacobian;           // d x n, or d x columns.size() when `columns` is given
  std::vector<Eigen::Index> columns;  // the state columns of a sparse Jacobian (empty: dense)
};

/// Returns the candidate for (i, j), or nullopt when it cannot be formed (e.g. landmark behind the sensor).
using CandidateFn = std::function<std::optional<Candidate>(int sighting, int landmark)>;

struct AssociationProblem {
  int sightings = 0, landmarks = 0;
  const Eigen::MatrixXd* covariance = nullptr;  // P, n x n
  std::vector<Eigen::MatrixXd> noise;           // R_i per sighting
  CandidateFn candidate;
  double individual_gate = 9.21;         // chi-square, per sighting (2 dof at 99 %)
  double joint_gate_probability = 0.99;  // for the joint test's chi-square with the stacked dimension
  double work_budget = 5e7;              // floating-point operations (about 50 ms); <= 0: unbounded
};

/// For each sighting, the landmark index it is paired with, or -1.
using Hypothesis = std::vector<int>;

/// Squared Mahalanobis distance of sighting i to landmark j (infinity when no candidate).
double individual_distance(const AssociationProblem& p, int i, int j);

Hypothesis nearest_neighbour(const AssociationProblem& p);

/// JCBB; `max_nodes` bounds the search (the best hypothesis found so far is returned when it is reached), and
/// `p.work_budget` its work (see the file comment).
Hypothesis joint_compatibility_branch_and_bound(const AssociationProblem& p, int max_nodes = 100000);

/// JCBB with what its budget did to it.
struct BoundedAssociation {
  Hypothesis pairing;
  int examined = 0;        // sightings [0, examined) were tested against every landmark; the others are unpaired
  bool exhausted = false;  // the budget ran out (pairing: nearest neighbour when it ran out in the search)
  double work = 0;         // operations charged
};
BoundedAssociation associate_bounded(const AssociationProblem& p, int max_nodes = 100000);

/// D2 of a whole hypothesis (the joint test statistic), and its dimension.
double joint_distance(const AssociationProblem& p, const Hypothesis& h, int* dimension = nullptr);

}  // namespace sextant::assoc
