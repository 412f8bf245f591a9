#pragma once
// Candidate tuples of an S-sensor passive scan and their association costs (source C eq. 7 and 19-21; assoc.md
// §1.3, §1.6, §1.7).  A tuple takes one detection per sensor or none (index 0 = missed); it needs at least two
// real detections.  Tuples are built sensor by sensor and pruned as soon as the detections so far fail the
// triangulation chi-square gate; a tuple whose cost is not negative is dropped (declaring its detections false
// alarms costs 0).
//   classic:  sum_real [ -ln(P_D / (lambda sqrt|2 pi R|)) + 1/2 nu' R^-1 nu ] - sum_missed ln(1 - P_D)
//   kl:       the 1/2 nu' R^-1 nu term replaced by KL(N(z, R) || N(z_hat, J P J'))
//   renyi:    replaced by SD_alpha(N(z, R), N(z_hat, J P J')) / alpha  (equal to 1/2 nu' R^-1 nu when the two
//             covariances are equal; the symmetric Renyi divergence of source C eq. 19-21)
// lambda is the false-alarm density per rad^2 of measurement space, z_hat = h(x_hat) the pseudo-measurement.
#include "assoc/triangulation.hpp"

#include <string>
#include <vector>

namespace sextant::assoc {

enum class CostKind { kClassic, kKl, kRenyi };

struct CostOptions {
  CostKind kind = CostKind::kClassic;
  double alpha = 0.5;              // Renyi order, in (0, 1)
  double p_detect = 0.9;           // in (0, 1]
  double clutter_density = 1.0;    // false alarms per rad^2 (lambda); > 0
  double gate_probability = 0.9999;  // chi-square gate on the triangulation residual (2m - 3 dof)
};

struct Detection {
  double azimuth = 0, elevation = 0, sigma_azimuth = 0.005, sigma_elevation = 0.005;
};

/// One scan round: per sensor its position and detections.
struct Scan {
  std::vector<Eigen::Vector3d> sensors;
  std::vector<std::vector<Detection>> detections;
};

struct Tuple {
  std::vector<int> index;  // per sensor: 0 = missed, k = detection k - 1
  double cost = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
};

/// Every gated tuple with negative cost.
std::vector<Tuple> build_tuples(const Scan& scan, const CostOptions& options);

/// The cost of one tuple (+infinity when it fails the gate or the geometry is degenerate).
double tuple_cost(const Scan& scan, const std::vector<int>& index, const CostOptions& options, Triangulation* t = nullptr);

CostKind cost_kind_from_string(const std::string& s);  // "classic", "kl", "renyi"; throws std::invalid_argument

}  // namespace sextant::assoc
