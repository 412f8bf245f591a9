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
#include "estimators/graph/factor_graph.hpp"

#include <istream>
#include <string>

namespace sextant::graph {

struct G2oGraph {
  FactorGraph graph;
  int dimension = 2;          // 2 or 3
  bool had_vertices = false;  // false: every pose was created from the edges and needs initializing
};

G2oGraph read_g2o(const std::string& path);
/// The same from a stream (g2o text in memory); `name` stands for the file in error messages.
G2oGraph read_g2o(std::istream& in, const std::string& name);
/// Writes vertices (current estimates), FIX lines, and the factors g2o can express (relative poses and point
/// positions).  Throws std::runtime_error when the file cannot be written.
void write_g2o(const std::string& path, const FactorGraph& graph);

}  // namespace sextant::graph
