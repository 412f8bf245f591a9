#pragma once
// g2o's text format for graphs: read into a FactorGraph, write back.
// Vertices: VERTEX_SE2 id x y theta | VERTEX_SE3:QUAT id x y z qx qy qz qw | VERTEX_XY id x y |
//           VERTEX_TRACKXYZ id x y z.
// Edges:    EDGE_SE2 i j dx dy dtheta I(6, upper triangle) | EDGE_SE3:QUAT i j x y z qx qy qz qw I(21) |
//           EDGE_SE2_XY pose point x y I(3) | EDGE_SE3_TRACKXYZ pose point param x y z I(6).
// Other:    PARAMS_SE3OFFSET id x y z qx qy qz qw (sensor offsets used by EDGE_SE3_TRACKXYZ) | FIX id...
// Comments (#), blank lines and edges with i > j are fine.  A file with no vertex lines gets its poses from the
// edges (initialized by odometry, see initialization.hpp).  An unknown tag or a malformed line is a
// std::runtime_error "FILE:LINE: message".
//
// Information matrices must be symmetric positive definite (the optimizer's weights).  Some published files are
// not: SE-Sync's cubicle.g2o has edges whose matrices are indefinite (smallest eigenvalue -157094 on its edge 2).
// By default such a file is refused with an IndefiniteInformationError naming every bad edge at once (count, then
// the first few as FILE:LINE with the smallest eigenvalue).  On request the reader repairs them instead:
//  - kRepair: the nearest positive definite matrix in the Frobenius norm, up to a floor: Omega = V diag(l) V'
//    becomes V diag(max(l, eps)) V' with eps = 1e-6 x the largest |l| (clipping the negative eigenvalues to 0 is
//    Higham's nearest positive semidefinite matrix; the floor keeps the normal equations positive definite, and
//    says "almost nothing is known" in the directions the file got wrong);
//  - kDiagonal: only the diagonal, each entry floored the same way (drops the correlations, keeps each
//    coordinate's own weight).
#include "estimators/graph/factor_graph.hpp"

#include <istream>
#include <stdexcept>
#include <string>
#include <vector>

namespace sextant::graph {

enum class InformationPolicy { kReject, kRepair, kDiagonal };
/// The policy spelt "reject", "repair" or "diagonal" (`sextant optimize --information`); throws
/// std::invalid_argument naming the spellings for any other name.
InformationPolicy information_policy_from_name(const std::string& name);
const char* information_policy_name(InformationPolicy policy);
std::vector<std::string> information_policy_names();

struct G2oReadOptions {
  InformationPolicy information = InformationPolicy::kReject;
};

/// A file with information matrices that are not positive definite (or not finite), read with kReject.
struct IndefiniteInformationError : std::runtime_error {
  using std::runtime_error::runtime_error;
  int edges = 0;  // how many edges are bad
};

struct G2oGraph {
  FactorGraph graph;
  int dimension = 2;             // 2 or 3
  bool had_vertices = false;     // false: every pose was created from the edges and needs initializing
  int repaired_information = 0;  // edges whose information matrix was repaired (kRepair / kDiagonal)
};

G2oGraph read_g2o(const std::string& path, const G2oReadOptions& options = {});
/// The same from a stream (g2o text in memory); `name` stands for the file in error messages.
G2oGraph read_g2o(std::istream& in, const std::string& name, const G2oReadOptions& options = {});

/// The information matrix `I` made positive definite as `policy` says (kReject: returned unchanged); see above.
Eigen::MatrixXd repair_information(const Eigen::MatrixXd& I, InformationPolicy policy);
/// Writes vertices (current estimates), FIX lines, and the factors g2o can express (relative poses and point
/// positions; each distinct sensor offset of the 3-D point factors as a PARAMS_SE3OFFSET line, numbered from 0).
/// Throws std::runtime_error when the file cannot be written, std::invalid_argument for a vector variable (g2o has no
/// vertex for a velocity or a bias).
void write_g2o(const std::string& path, const FactorGraph& graph);

}  // namespace sextant::graph
