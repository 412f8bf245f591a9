#include "estimators/filter/planar_ekf.hpp"

#include "estimators/lie/lie_archive.hpp"

#include "assoc/landmark/jcbb.hpp"
#include "estimators/filter/landmark_admission.hpp"
#include "estimators/filter/state_augmentation.hpp"
#include "estimators/spd_matrix.hpp"

#include <cmath>

namespace sextant::filter {

void PlanarEkf::initialize(const SE2& pose, const Eigen::Matrix3d& covariance) {
  x_ = Eigen::VectorXd::Zero(3);
  x_ << pose.translation(), pose.angle();
  P_ = covariance;
  slot_.clear();
  initialized_ = true;
}

Eigen::Vector3d PlanarEkf::motion(const Eigen::Vector3d& x, const SE2& d, Eigen::Matrix3d* F, Eigen::Matrix3d* G) {
  const double c = std::cos(x[2]), s = std::sin(x[2]);
  const double dx = d.translation().x(), dy = d.translation().y();
  if (F) {
    *F = Eigen::Matrix3d::Identity();
    (*F)(0, 2) = -s * dx - c * dy;
    (*F)(1, 2) = c * dx - s * dy;
  }
  const double th = x[2] + d.angle();
  if (G) {
    *G = Eigen::Matrix3d::Identity();
    G->topLeftCorner<2, 2>() = SO2(th).matrix();
  }
  return {x[0] + c * dx - s * dy, x[1] + s * dx + c * dy, wrap_angle(th)};
}

Eigen::Vector2d PlanarEkf::observation(const Eigen::Vector3d& r, const Eigen::Vector2d& l,
                                       Eigen::Matrix<double, 2, 3>* Hx, Eigen::Matrix2d* Hl) {
  const Eigen::Vector2d d = l - r.head<2>();
  const double q = d.squaredNorm(), sq = std::sqrt(q);
  if (Hx) *Hx << -d.x() / sq, -d.y() / sq, 0, d.y() / q, -d.x() / q, -1;
  if (Hl) *Hl << d.x() / sq, d.y() / sq, -d.y() / q, d.x() / q;
  return {sq, wrap_angle(std::atan2(d.y(), d.x()) - r[2])};
}

Health PlanarEkf::predict(const SE2& delta, const Eigen::Matrix3d& Q) {
  Eigen::Matrix3d F, G;
  const Eigen::Vector3d robot = motion(x_.head<3>(), delta, &F, &G);
  const Eigen::Index n = x_.size();
  // Only the robot rows and columns change: P_rr = F P_rr F' + G Q G', P_rl = F P_rl.  Both are computed aside and
  // checked before they replace the state's.
  Eigen::Matrix3d Prr = F * P_.topLeftCorner<3, 3>() * F.transpose() + G * Q * G.transpose();
  Prr = symmetrized(Prr);
  const Eigen::MatrixXd Prl = F * P_.topRightCorner(3, n - 3);
  Health h = estimate_health(robot, Prr, 3);
  if (h == Health::kHealthy && !Prl.allFinite()) h = Health::kNonFinite;
  if (h != Health::kHealthy) {
    refusals_.count(h);
    return h;
  }
  x_.head<3>() = robot;
  P_.topLeftCorner<3, 3>() = Prr;
  if (n > 3) {
    P_.topRightCorner(3, n - 3) = Prl;
    P_.bottomLeftCorner(n - 3, 3) = Prl.transpose();
  }
  return h;
}

UpdateResult PlanarEkf::counted(UpdateResult r) {
  if (r.reason == UpdateReason::kNonFinite)
    refusals_.count(Health::kNonFinite);
  else if (r.reason == UpdateReason::kIndefinite)
    refusals_.count(Health::kIndefinite);
  return r;
}

UpdateResult PlanarEkf::observe(int64_t id, double range, double bearing, const Eigen::Matrix2d& R) {
  UpdateResult out;
  if (!std::isfinite(range) || !std::isfinite(bearing) || !R.allFinite() || range <= 0) {
    out.reason = UpdateReason::kNonFinite;
    return out;
  }
  Eigen::Vector2d z(range, bearing);
  Eigen::Matrix<double, 2, 3> Hx;
  Eigen::Matrix2d Hl;
  Eigen::Vector2d predicted;
  // H is zero but for the robot's 3 columns and the landmark's 2: P H' and H P H' in O(n).
  Eigen::MatrixXd PHt, HPHt;
  if (auto k = known_.find(id); k != known_.end()) {
    predicted = observation(x_.head<3>(), k->second, &Hx, nullptr);
    PHt = P_.leftCols<3>() * Hx.transpose();
    HPHt = Hx * PHt.topRows<3>();
  } else if (auto s = slot_.find(id); s != slot_.end()) {
    predicted = observation(x_.head<3>(), x_.segment<2>(s->second), &Hx, &Hl);
    PHt = P_.leftCols<3>() * Hx.transpose() + P_.middleCols<2>(s->second) * Hl.transpose();
    HPHt = Hx * PHt.topRows<3>() + Hl * PHt.middleRows<2>(s->second);
  } else {
    return counted(admit_new_landmark(options_.slam, id, slot_.size(), options_.max_landmarks,
                                      [&] { return augment(id, range, bearing, R); }));
  }
  if (predicted[0] < 1e-6) {
    out.reason = UpdateReason::kSingular;
    return out;
  }
  Eigen::VectorXd r = z - predicted;
  r[1] = wrap_angle(r[1]);
  out = counted(kalman_update_from(x_, P_, r, PHt, HPHt, R, options_.gate));
  x_[2] = wrap_angle(x_[2]);
  return out;
}

namespace {

// d(right perturbation of X)/d[x, y, theta]: delta_body = blockdiag(R(theta)^T, 1) delta_global.
Eigen::Matrix3d body_from_global(double theta) {
  Eigen::Matrix3d B = Eigen::Matrix3d::Identity();
  B.topLeftCorner<2, 2>() = SO2(theta).matrix().transpose();
  return B;
}

// r = Log(h^-1 Z) with h = h_hat Exp(J dx): r(dx) ~ r - Jr^-1(r) Ad(E^-1) J dx, E = h_hat^-1 Z.  Returns r and
// D = Jr^-1(r) Ad(E^-1), so that H = D J.
Eigen::Vector3d right_innovation(const SE2& h, const SE2& z, Eigen::Matrix3d* D) {
  const SE2 E = h.inverse() * z;
  Eigen::Matrix3d Jr_inv;
  const Eigen::Vector3d r = E.log(&Jr_inv);
  if (D) *D = Jr_inv * E.inverse().adjoint();
  return r;
}

}  // namespace

Eigen::Vector3d PlanarEkf::relative_pose_innovation(const Eigen::Vector3d& c, const Eigen::Vector3d& x, const SE2& z,
                                                    Eigen::Matrix3d* H_clone, Eigen::Matrix3d* H_robot) {
  const SE2 C(c[0], c[1], c[2]), X(x[0], x[1], x[2]);
  Eigen::Matrix3d J_c, J_x, D;
  const SE2 h = C.between(X, &J_c, &J_x);
  const Eigen::Vector3d r = right_innovation(h, z, &D);
  if (H_clone) *H_clone = D * J_c * body_from_global(c[2]);
  if (H_robot) *H_robot = D * J_x * body_from_global(x[2]);
  return r;
}

Eigen::Vector3d PlanarEkf::pose_innovation(const SE2& frame, const Eigen::Vector3d& x, const SE2& z,
                                           Eigen::Matrix3d* H_robot) {
  Eigen::Matrix3d D;
  const Eigen::Vector3d r = right_innovation(frame.inverse() * SE2(x[0], x[1], x[2]), z, &D);
  if (H_robot) *H_robot = D * body_from_global(x[2]);
  return r;
}

int PlanarEkf::add_pose_clone() {
  const Eigen::Index n = x_.size();
  x_.conservativeResize(n + 3);
  P_.conservativeResize(n + 3, n + 3);
  const int index = static_cast<int>(n);
  refresh_clone(index);
  return index;
}

void PlanarEkf::refresh_clone(int index) {
  x_.segment<3>(index) = x_.head<3>();
  P_.middleRows<3>(index) = P_.topRows<3>();
  P_.middleCols<3>(index) = P_.leftCols<3>();
  P_.block<3, 3>(index, index) = P_.topLeftCorner<3, 3>();
}

UpdateResult PlanarEkf::observe_relative_pose(int clone, const SE2& z, const Eigen::Matrix3d& R,
                                              const std::array<bool, 3>& rows, double gate) {
  Eigen::Matrix3d Hc, Hx;
  const Eigen::Vector3d r = relative_pose_innovation(x_.segment<3>(clone), x_.head<3>(), z, &Hc, &Hx);
  return update_rows(r, Hx, clone, Hc, R, rows, gate);
}

UpdateResult PlanarEkf::observe_pose(const SE2& frame, const SE2& z, const Eigen::Matrix3d& R,
                                     const std::array<bool, 3>& rows, double gate) {
  Eigen::Matrix3d Hx;
  const Eigen::Vector3d r = pose_innovation(frame, x_.head<3>(), z, &Hx);
  return update_rows(r, Hx, -1, Eigen::Matrix3d::Zero(), R, rows, gate);
}

UpdateResult PlanarEkf::update_rows(const Eigen::Vector3d& r, const Eigen::Matrix3d& Hx, int other,
                                    const Eigen::Matrix3d& Ho, const Eigen::Matrix3d& R,
                                    const std::array<bool, 3>& rows, double gate) {
  UpdateResult out;
  if (!r.allFinite() || !R.allFinite() || !Hx.allFinite() || !Ho.allFinite()) {
    out.reason = UpdateReason::kNonFinite;
    return out;
  }
  std::vector<int> use;
  for (int i = 0; i < 3; ++i)
    if (rows[static_cast<size_t>(i)]) use.push_back(i);
  const auto m = static_cast<Eigen::Index>(use.size());
  if (m == 0) {
    out.reason = UpdateReason::kNoComponents;
    return out;
  }
  Eigen::MatrixXd Hx_m(m, 3), Ho_m(m, 3), R_m(m, m);
  Eigen::VectorXd r_m(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    Hx_m.row(i) = Hx.row(use[static_cast<size_t>(i)]);
    Ho_m.row(i) = Ho.row(use[static_cast<size_t>(i)]);
    r_m[i] = r[use[static_cast<size_t>(i)]];
    for (Eigen::Index j = 0; j < m; ++j) R_m(i, j) = R(use[static_cast<size_t>(i)], use[static_cast<size_t>(j)]);
  }
  // H is zero but for the robot's 3 columns (and the clone's 3): P H' and H P H' in O(n).
  Eigen::MatrixXd PHt = P_.leftCols<3>() * Hx_m.transpose();
  if (other >= 0) PHt += P_.middleCols<3>(other) * Ho_m.transpose();
  Eigen::MatrixXd HPHt = Hx_m * PHt.topRows<3>();
  if (other >= 0) HPHt += Ho_m * PHt.middleRows<3>(other);
  out = counted(kalman_update_from(x_, P_, r_m, PHt, HPHt, R_m, gate));
  x_[2] = wrap_angle(x_[2]);
  if (other >= 0) x_[other + 2] = wrap_angle(x_[other + 2]);
  return out;
}

Health PlanarEkf::augment(int64_t id, double range, double bearing, const Eigen::Matrix2d& R) {
  const Eigen::Index n = x_.size();
  const double a = x_[2] + bearing, c = std::cos(a), s = std::sin(a);
  const Eigen::Vector2d l(x_[0] + range * c, x_[1] + range * s);
  Eigen::Matrix<double, 2, 3> Jx;
  Jx << 1, 0, -range * s, 0, 1, range * c;
  Eigen::Matrix2d Jz;
  Jz << c, -range * s, s, range * c;
  Eigen::MatrixXd P = augmented_covariance(P_, Jx, Jz, R);
  // Only the new rows are new: their block must be a covariance and every number finite.
  Health h = estimate_health(l, P.bottomRightCorner<2, 2>(), 2);
  if (h == Health::kHealthy && !P.bottomRows<2>().allFinite()) h = Health::kNonFinite;
  if (h != Health::kHealthy) return h;
  x_.conservativeResize(n + 2);
  x_.tail<2>() = l;
  P_ = std::move(P);
  slot_[id] = static_cast<int>(n);
  return h;
}

// Every landmark, known or in the state, as an index for the association: (id, in state).
std::vector<std::pair<int64_t, bool>> PlanarEkf::association_index() const {
  std::vector<std::pair<int64_t, bool>> ids;
  for (const auto& [id, p] : known_) ids.push_back({id, false});
  for (const auto& [id, k] : slot_) ids.push_back({id, true});
  return ids;
}

// Joint compatibility over the sightings and the indexed landmarks, within the work budget (assoc/landmark/jcbb.hpp).
assoc::BoundedAssociation PlanarEkf::associate(const std::vector<Sighting>& sightings,
                                               const std::vector<std::pair<int64_t, bool>>& ids) const {
  assoc::AssociationProblem problem;
  problem.sightings = static_cast<int>(sightings.size());
  problem.landmarks = static_cast<int>(ids.size());
  problem.covariance = &P_;
  problem.individual_gate = options_.gate;
  for (const auto& s : sightings) problem.noise.push_back(s.covariance);
  problem.candidate = [&](int i, int j) -> std::optional<assoc::Candidate> {
    const auto [id, in_state] = ids[static_cast<size_t>(j)];
    const Eigen::Vector2d l = in_state ? Eigen::Vector2d(x_.segment<2>(slot_.at(id))) : known_.at(id);
    Eigen::Matrix<double, 2, 3> Hx;
    Eigen::Matrix2d Hl;
    const Eigen::Vector2d h = observation(x_.head<3>(), l, &Hx, &Hl);
    if (h[0] < 1e-6) return std::nullopt;
    assoc::Candidate c;
    c.innovation = Eigen::Vector2d(sightings[static_cast<size_t>(i)].range - h[0],
                                   wrap_angle(sightings[static_cast<size_t>(i)].bearing - h[1]));
    // H is zero but for the robot's 3 columns and the landmark's 2: given sparse, each test costs O(1), not O(n^2).
    c.jacobian.resize(2, in_state ? 5 : 3);
    c.jacobian.leftCols<3>() = Hx;
    c.columns = {0, 1, 2};
    if (in_state) {
      c.jacobian.rightCols<2>() = Hl;
      c.columns.push_back(slot_.at(id));
      c.columns.push_back(slot_.at(id) + 1);
    }
    return c;
  };
  problem.work_budget = options_.association_budget;
  assoc::BoundedAssociation a;
  if (problem.landmarks > 0)
    a = assoc::associate_bounded(problem, 20000);
  else
    a.pairing.assign(sightings.size(), -1), a.examined = problem.sightings;
  return a;
}

// Tentative landmarks: matched by distance in the map frame, confirmed after enough sightings.
void PlanarEkf::admit_tentative(const std::vector<Sighting>& sightings, const std::vector<size_t>& unpaired,
                                UpdateBudget& budget, AssociationOutcome& out) {
  for (auto& t : tentative_) ++t.idle;
  for (size_t i : unpaired) {
    const auto& s = sightings[i];
    const double a = x_[2] + s.bearing;
    const Eigen::Vector2d p(x_[0] + s.range * std::cos(a), x_[1] + s.range * std::sin(a));
    Tentative* match = nullptr;
    for (auto& t : tentative_)
      if ((t.position - p).norm() < options_.tentative_radius &&
          (!match || (t.position - p).norm() < (match->position - p).norm()))
        match = &t;
    if (match == nullptr) {
      if (static_cast<int>(tentative_.size()) >= options_.max_landmarks) {
        ++out.over_budget;  // as many candidates as the map may hold: a flood of new sightings is not hoarded
        continue;
      }
      tentative_.push_back({p, 1, 0, s});
      ++out.tentative;
      continue;
    }
    match->position = (match->position * match->seen + p) / (match->seen + 1);
    ++match->seen;
    match->idle = 0;
    match->last = s;
    if (match->seen >= options_.confirmations && static_cast<int>(slot_.size()) < options_.max_landmarks &&
        budget.spend(x_.size())) {
      if (const Health h = augment(next_id_, s.range, s.bearing, s.covariance); h != Health::kHealthy) {
        refusals_.count(h);
      } else {
        ++next_id_;
        ++out.confirmed;
      }
      match->seen = -1;  // consumed
    }
  }
  std::erase_if(tentative_, [&](const Tentative& t) { return t.seen < 0 || t.idle > options_.tentative_lifetime; });
}

AssociationOutcome PlanarEkf::observe_unidentified(const std::vector<Sighting>& sightings, UpdateBudget& budget) {
  AssociationOutcome out;
  if (sightings.empty()) return out;
  const auto ids = association_index();
  const assoc::BoundedAssociation a = associate(sightings, ids);
  const assoc::Hypothesis& h = a.pairing;
  out.exhausted = a.exhausted;
  // The paired sightings update one after the other (equal to the joint update for a linearized model).
  std::vector<size_t> unpaired;
  for (size_t i = 0; i < sightings.size(); ++i) {
    if (h[i] < 0 && static_cast<int>(i) >= a.examined) {
      ++out.over_budget;  // never compared with the map: neither paired nor a new landmark
      continue;
    }
    if (h[i] < 0) {
      unpaired.push_back(i);
      continue;
    }
    if (!budget.spend(x_.size())) {
      ++out.over_budget;
      continue;
    }
    const auto r = observe(ids[static_cast<size_t>(h[i])].first, sightings[i].range, sightings[i].bearing,
                           sightings[i].covariance);
    r.accepted ? ++out.paired : ++out.gated;
  }
  if (options_.slam) admit_tentative(sightings, unpaired, budget, out);
  return out;
}

std::map<int64_t, Eigen::Vector2d> PlanarEkf::landmarks() const {
  std::map<int64_t, Eigen::Vector2d> out = known_;
  for (const auto& [id, k] : slot_) out[id] = x_.segment<2>(k);
  return out;
}

void PlanarEkf::save(archive::ArchiveWriter& w) const {
  w(initialized_)(x_)(P_)(known_)(slot_)(next_id_)(refusals_.non_finite)(refusals_.indefinite);
  w(static_cast<uint64_t>(tentative_.size()));
  for (const Tentative& t : tentative_) w(t.position)(t.seen)(t.idle)(t.last.range)(t.last.bearing)(t.last.covariance);
}

void PlanarEkf::load(archive::ArchiveReader& r) {
  r(initialized_)(x_)(P_)(known_)(slot_)(next_id_)(refusals_.non_finite)(refusals_.indefinite);
  if (x_.size() < 3 || P_.rows() != x_.size() || P_.cols() != x_.size())
    r.fail("an EKF state whose covariance does not match it");
  for (const auto& [id, slot] : slot_)
    if (slot < 3 || slot + 2 > x_.size()) r.fail("an EKF landmark slot outside the state");
  tentative_.resize(r.count(1, "the tentative landmarks"));
  for (Tentative& t : tentative_) r(t.position)(t.seen)(t.idle)(t.last.range)(t.last.bearing)(t.last.covariance);
}

}  // namespace sextant::filter
