#pragma once
// A g2o pose graph as an LCM log, so it can be replayed through sextantd: the chain of consecutive vertex ids
// becomes odometry (odometry_t: the composed chain, with each edge's covariance as increment covariance), every
// other relative-pose edge a loop closure (loop_closure_t between the two vertices' times).  Vertex k gets the
// time start + k * period.  Information matrices are mapped from g2o's tangent to sextant's: planar [x y theta] ->
// components (0, 1, 5); 3-D [t, qvec] -> [t, rotation vector], where qvec ~ phi / 2, so the rotation block is
// divided by 4 and the cross block by 2.
#include "estimators/graph/factor_graph.hpp"

#include <cstdint>
#include <string>

namespace sextant::tools {

struct G2oConversion {
  int64_t odometry = 0, loop_closures = 0, skipped_edges = 0;
};

struct G2oConversionOptions {
  int64_t start_utime = 1'700'000'000'000'000;
  int64_t period_us = 100'000;  // one vertex every 0.1 s
  std::string source = "robot1";
};

/// Converts the graph read from `g2o_path` into `out_lcm`; with `gt_tum` non-empty, also writes the file's vertex
/// estimates as a TUM trajectory.  Throws std::runtime_error (with file:line for parse errors).
G2oConversion convert_g2o(const std::string& g2o_path, const std::string& out_lcm, const std::string& gt_tum,
                          const G2oConversionOptions& options = {});

/// The 6x6 information of sextant's tangent for a g2o relative-pose factor's information.
Eigen::Matrix<double, 6, 6> g2o_information_to_sextant(const Eigen::MatrixXd& info, bool planar);

}  // namespace sextant::tools
