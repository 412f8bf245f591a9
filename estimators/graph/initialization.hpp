#pragma once
// Initial estimates for a factor graph.
//  - Odometry (spanning tree): from the lowest-id pose (or the fixed ones), every pose is reached through
//    relative-pose factors, preferring the chain of consecutive ids, and set to X_i * Z_ij (or X_j * Z_ij^-1).
//  - Chordal relaxation (Martinec & Pajdla 2007; Carlone et al., "Initialization techniques for 3D SLAM", ICRA
//    2015): rotations first, as the linear least-squares problem min sum kappa_ij |R_j - R_i Z_ij|_F^2 over
//    unconstrained matrices, each projected back onto SO(d) by SVD; then translations by linear least squares
//    min sum tau_ij |t_j - t_i - R_i t_ij|^2 with those rotations.  Gets 3-D graphs into the basin of the global
//    optimum where Gauss-Newton from odometry stops in a local minimum (torus, sphere, grid).  Both problems
//    separate: row r of R_j - R_i Z_ij involves row r of each rotation only, with one normal matrix for all rows,
//    and the isotropic weights tau give each coordinate of t the graph's weighted Laplacian; so one sparse LDL' of
//    size n d with d right-hand sides, and one of size n with d (n unknown poses).
//  - SGD (Olson, Leonard, Teller, "Fast iterative optimization of pose graphs with poor initial estimates",
//    ICRA 2006), planar graphs: poses in Olson's incremental parameterization (pose j = sum of increments 1..j in
//    global x, y, theta); each constraint (a, b) in turn removes a fraction of its global-frame residual
//    r = (X_a (+) Z_ab) - X_b, spread evenly over the increments a+1..b (a poses' ramp, kept in two Fenwick trees so
//    a step costs O(log n)).  The fraction per dimension is alpha_t * w / (w + w_median), w the constraint's
//    information in the global frame, alpha_t = 1 / (1 + t) over sweeps t.  Deviation from the paper: the
//    preconditioner spreads the correction by path length instead of by each increment's accumulated information.
// Points observed by position factors are placed from their first observation.
#include "estimators/graph/factor_graph.hpp"

#include <cstdint>
#include <string>

namespace sextant::graph {

/// Returns the number of variables it could not reach (disconnected); those keep their values.
int initialize_by_odometry(FactorGraph& graph);

/// Returns an empty string on success, else why it failed (the graph is then left as it was).
std::string initialize_chordal(FactorGraph& graph);

/// `--init auto`: the chordal relaxation's estimate when its chi2 is below the current estimate's (measured on the
/// graph's own factors), else the current estimate, restored.  Chordal helps where the current estimate is
/// odometry or far from the optimum (torus3D: 2.9e6 from the file, chordal ends Gauss-Newton at 14574.75 against
/// 19972.36 from the file, 12x faster; MIT 41.16 against 770.66); it was lower on 18 of the 19 shared sets, even
/// intel's near-optimal vertices (47.8 against 551.7).  Carlone's input_INTEL_g2o keeps its vertices (the chordal
/// estimate is worse there; both end at 215.83), as does a file already at the optimum.
/// Returns true when the chordal estimate was taken.
bool initialize_auto(FactorGraph& graph);

/// Olson's SGD from the current estimate (planar graphs; 3-D graphs get an error, use chordal).  Returns an empty
/// string on success, else why it did not run.
std::string initialize_sgd(FactorGraph& graph, int sweeps = 100, uint64_t seed = 1);

}  // namespace sextant::graph
