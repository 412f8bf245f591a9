#pragma once
// Initial estimates for a factor graph.
//  - Odometry (spanning tree): from the lowest-id pose (or the fixed ones), every pose is reached through
//    relative-pose factors, preferring the chain of consecutive ids, and set to X_i * Z_ij (or X_j * Z_ij^-1).
//  - Chordal relaxation (Martinec & Pajdla 2007; Carlone et al., "Initialization techniques for 3D SLAM", ICRA
//    2015): rotations first, as the linear least-squares problem min sum kappa_ij |R_j - R_i Z_ij|_F^2 over
//    unconstrained matrices, each projected back onto SO(d) by SVD; then translations by linear least squares
//    min sum tau_ij |t_j - t_i - R_i t_ij|^2 with those rotations.  Gets 3-D graphs into the basin of the global
//    optimum where Gauss-Newton from odometry stops in a local minimum (torus, sphere, grid).
// Points observed by position factors are placed from their first observation.
#include "estimators/graph/factor_graph.hpp"

#include <string>

namespace sextant::graph {

/// Returns the number of variables it could not reach (disconnected); those keep their values.
int initialize_by_odometry(FactorGraph& graph);

/// Returns an empty string on success, else why it failed (the graph is then left as it was).
std::string initialize_chordal(FactorGraph& graph);

}  // namespace sextant::graph
