#pragma once
// Candidate tuples of an S-sensor passive scan and their association costs (the passive-association paper, "Data
// association algorithm for passive sensor based on position estimation uncertainty", Computer Measurement &
// Control 2015, eq. 7 and 19-21; the likelihood ratio of Pattipati et al., IEEE TAC 37(2) 1992).  A tuple takes one detection per sensor or none (index 0 = missed); it needs at least two
// real detections.  A tuple whose cost is not negative is dropped (declaring its detections false alarms costs 0).
//   classic:  sum_real [ -ln(P_D / (lambda_s sqrt|2 pi R|)) + 1/2 nu' R^-1 nu ] - sum_missed ln(1 - P_D)
//   kl:       the 1/2 nu' R^-1 nu term replaced by the symmetric KL divergence
//             1/2 [KL(N(z, R) || N(z_hat, J P J')) + KL(N(z_hat, J P J') || N(z, R))] (the paper's symmetrization,
//             eq. 19-21, at alpha -> 1; equal to 1/2 nu' R^-1 nu when the covariances are equal).  It was
//             one-sided KL(N(z, R) || N(z_hat, J P J')) before, which is not the paper's divergence.
//   renyi:    replaced by SD_alpha(N(z, R), N(z_hat, J P J')) / alpha  (equal to 1/2 nu' R^-1 nu when the two
//             covariances are equal; the symmetric Renyi divergence of eq. 19-21)
//   + target prior (optional, every kind):  - ln(mu_T sqrt|2 pi P|)
// lambda_s is sensor s's false-alarm density per rad^2 of azimuth x elevation (expected false alarms per scan
// divided by the area of its field of view, field_of_view.hpp), z_hat = h(x_hat) the pseudo-measurement, P the
// triangulation covariance.
//
// The target-prior term.  The classic cost compares "one target at x_hat" with "all false alarms", plugging in the
// best-fitting position x_hat; the proper likelihood ratio integrates the position over the target prior, here a
// uniform density mu_T of expected targets per unit volume (a Poisson target field, as the clutter is a Poisson
// field):  integral mu_T prod_s N(z_s; h_s(x), R_s) dx  ~=  mu_T prod_s N(z_s; h_s(x_hat), R_s) sqrt|2 pi P|
// (Laplace).  The extra factor is the prior probability that a target lies in the tuple's uncertainty volume.  It
// charges every tuple for the three position coordinates its detections had to fit: a ghost (false alarms or
// detections of different targets whose lines of sight happen to meet) no longer gets a free fit, which cuts
// ghost tuples under clutter.  mu_T = 0 leaves the term out (the classic generalized likelihood ratio).
//
// Gating, cheapest first: every pair of detections of two sensors is tested once (lines of sight
// meeting in front of both sensors within a noise-scaled miss distance, then the chi-square gate on the pair's
// triangulation residual); a partial tuple is only extended by detections compatible with each of its detections
// (a clique across the lists), and partial tuples of 3 or more detections must pass the triangulation residual
// gate (2m - 3 degrees of freedom) before they are extended further.
#include "assoc/triangulation.hpp"

#include <string>
#include <vector>

namespace sextant::assoc {

enum class CostKind { kClassic, kKl, kRenyi };

struct CostOptions {
  CostKind kind = CostKind::kClassic;
  double alpha = 0.5;                          // Renyi order, in (0, 1)
  double p_detect = 0.9;                       // in (0, 1]
  double clutter_density = 1.0;                // false alarms per rad^2 (lambda); > 0
  std::vector<double> sensor_clutter_density;  // per sensor (lambda_s, per rad^2); when non-empty it replaces
                                               // clutter_density and must have one entry per sensor
  double target_density = 0;  // mu_T, expected targets per unit volume (the position unit cubed); 0: no prior term
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

/// Every gated tuple with negative cost.  Throws std::invalid_argument when the scan and the options disagree
/// (detection lists per sensor, clutter densities per sensor).
std::vector<Tuple> build_tuples(const Scan& scan, const CostOptions& options);

/// The cost of one tuple (+infinity when it fails the gate or the geometry is degenerate).
double tuple_cost(const Scan& scan, const std::vector<int>& index, const CostOptions& options,
                  Triangulation* t = nullptr);

CostKind cost_kind_from_string(const std::string& s);  // "classic", "kl", "renyi"; throws std::invalid_argument
const char* cost_kind_name(CostKind kind);             // the spelling cost_kind_from_string reads

}  // namespace sextant::assoc
