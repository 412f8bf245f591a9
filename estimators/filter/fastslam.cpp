#include "estimators/filter/fastslam.hpp"

#include "estimators/lie/lie_archive.hpp"

#include <sstream>

#include "estimators/filter/low_variance_resampling.hpp"
#include "estimators/filter/planar_ekf.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <set>

namespace sextant::filter {

namespace {

constexpr double kLog2Pi = 1.8378770664093453;  // log(2 pi)
constexpr int64_t kUnidentifiedIdBase = int64_t{1} << 40;

bool symmetric_positive_definite(const Eigen::Matrix2d& R) {
  if (!R.allFinite() || std::abs(R(0, 1) - R(1, 0)) > 1e-9 * (1 + R.cwiseAbs().maxCoeff())) return false;
  return R(0, 0) > 0 && R.determinant() > 0;
}

/// log of the likelihood of a sighting exactly at the gate: the weight of "a new landmark" and of an outlier.
double log_new_landmark_likelihood(double gate, const Eigen::Matrix2d& R) {
  return -0.5 * gate - kLog2Pi - 0.5 * std::log(R.determinant());
}

/// Standard 2x2 EKF update of one landmark seen from a known pose (Joseph form).  False when degenerate.
bool update_landmark(MapLandmark& lm, const Eigen::Vector3d& pose, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  Eigen::Matrix2d H;
  const Eigen::Vector2d zhat = PlanarEkf::observation(pose, lm.mean, nullptr, &H);
  if (zhat[0] < 1e-6) return false;
  Eigen::Vector2d nu = z - zhat;
  nu[1] = wrap_angle(nu[1]);
  const Eigen::Matrix2d S = H * lm.covariance * H.transpose() + R;
  const Eigen::LLT<Eigen::Matrix2d> llt(S);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Matrix2d K = llt.solve(H * lm.covariance).transpose();  // Sigma H' S^-1
  lm.mean += K * nu;
  const Eigen::Matrix2d IKH = Eigen::Matrix2d::Identity() - K * H;
  const Eigen::Matrix2d P = IKH * lm.covariance * IKH.transpose() + K * R * K.transpose();
  lm.covariance = symmetrized(P);
  return true;
}

/// A landmark initialized by inverting the observation model at `pose`: mean and J_z R J_z'.
MapLandmark new_landmark(const Eigen::Vector3d& pose, const RangeBearing& s) {
  const double a = pose[2] + s.bearing, c = std::cos(a), sn = std::sin(a);
  MapLandmark lm;
  lm.mean = pose.head<2>() + s.range * Eigen::Vector2d(c, sn);
  Eigen::Matrix2d Jz;
  Jz << c, -s.range * sn, sn, s.range * c;
  const Eigen::Matrix2d P = Jz * s.covariance * Jz.transpose();
  lm.covariance = symmetrized(P);
  lm.id = s.id;
  lm.observations = 1;
  return lm;
}

}  // namespace

FastSlam::FastSlam(const FastSlamOptions& options) : options_(options), rng_(options.seed) {
  options_.particles = std::max(1, options_.particles);
}

void FastSlam::initialize(const SE2& pose, const Eigen::Matrix3d& covariance) {
  Particle p;
  p.pose.mean << pose.translation(), pose.angle();
  p.pose.covariance = symmetrized(covariance);
  particles_.assign(static_cast<size_t>(options_.particles), p);
  identified_slot_.clear();
  batches_ = 0;
  initialized_ = true;
}

Health FastSlam::health() const {
  for (const Particle& p : particles_) {
    if (!p.pose.mean.allFinite() || !std::isfinite(p.log_weight) || !p.pose.covariance.allFinite())
      return Health::kNonFinite;
    if ((p.pose.covariance.diagonal().array() < 0).any()) return Health::kIndefinite;
  }
  SE2 mean;
  Eigen::Matrix3d covariance;
  mixture(&mean, &covariance);
  Eigen::Vector3d m(mean.translation().x(), mean.translation().y(), mean.angle());
  return estimate_health(m, covariance, 3);
}

bool FastSlam::predict(const SE2& delta, const Eigen::Matrix3d& Q) {
  if (!initialized_ || !Q.allFinite() || !delta.translation().allFinite() || !std::isfinite(delta.angle()))
    return false;
  const Eigen::Matrix3d Qs = symmetrized(Q);
  if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(Qs, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() <
      -1e-12 * (1 + Qs.cwiseAbs().maxCoeff()))
    return false;
  Eigen::Matrix3d F, G;
  for (auto& p : particles_) {
    p.pose.mean = PlanarEkf::motion(p.pose.mean, delta, &F, &G);
    const Eigen::Matrix3d P = F * p.pose.covariance * F.transpose() + G * Qs * G.transpose();
    p.pose.covariance = symmetrized(P);
  }
  return true;
}

std::optional<FastSlam::ProposalStep> FastSlam::refine_proposal(PoseGaussian& g, const Eigen::Vector2d& landmark,
                                                                const Eigen::Matrix2d& landmark_covariance,
                                                                const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  Eigen::Matrix<double, 2, 3> Gs;
  Eigen::Matrix2d Gl;
  const Eigen::Vector2d zhat = PlanarEkf::observation(g.mean, landmark, &Gs, &Gl);
  if (!(zhat[0] >= 1e-6)) return std::nullopt;
  Eigen::Vector2d nu = z - zhat;
  nu[1] = wrap_angle(nu[1]);
  const Eigen::Matrix2d Qn = R + Gl * landmark_covariance * Gl.transpose();
  const Eigen::Matrix<double, 3, 2> PGt = g.covariance * Gs.transpose();
  const Eigen::Matrix2d L = Gs * PGt + Qn;
  const Eigen::LLT<Eigen::Matrix2d> llt(L);
  if (llt.info() != Eigen::Success) return std::nullopt;
  ProposalStep out;
  out.d2 = nu.dot(llt.solve(nu));
  const Eigen::Matrix2d Lc = llt.matrixL();
  out.log_likelihood = -0.5 * out.d2 - kLog2Pi - std::log(Lc(0, 0) * Lc(1, 1));
  const Eigen::Matrix<double, 3, 2> K = llt.solve(PGt.transpose()).transpose();  // P G_s' L^-1
  g.mean += K * nu;
  g.mean[2] = wrap_angle(g.mean[2]);
  const Eigen::Matrix3d IKG = Eigen::Matrix3d::Identity() - K * Gs;
  const Eigen::Matrix3d P = IKG * g.covariance * IKG.transpose() + K * Qn * K.transpose();
  g.covariance = symmetrized(P);
  return out;
}

Eigen::Vector3d FastSlam::sample(const PoseGaussian& g) {
  // Three draws in a fixed order (the order in which a constructor's arguments are evaluated is the compiler's, so
  // g++ and clang builds drew different particles from one seed); the last component first, as g++ builds did.
  const double n3 = normal_(rng_), n2 = normal_(rng_), n1 = normal_(rng_);
  const Eigen::Vector3d n(n1, n2, n3);
  if (g.covariance.isZero(0)) return g.mean;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(g.covariance);
  Eigen::Vector3d s = ldlt.vectorD().cwiseMax(0.0).cwiseSqrt().cwiseProduct(n);
  s = ldlt.matrixL() * s;
  s = ldlt.transpositionsP().transpose() * s;
  Eigen::Vector3d out = g.mean + s;
  out[2] = wrap_angle(out[2]);
  return out;
}

bool FastSlam::valid(const RangeBearing& s) const {
  return std::isfinite(s.range) && std::isfinite(s.bearing) && s.range > 0 && symmetric_positive_definite(s.covariance);
}

// Per sighting of the batch: where its landmark lives.
enum class Kind { known, identified, identified_new, unidentified };

struct FastSlam::Pending {
  size_t sighting;
  bool create;
  bool in_unidentified;  // which tree
  int32_t slot;
};

FastSlamBatchOutcome FastSlam::observe(const std::vector<RangeBearing>& sightings) {
  FastSlamBatchOutcome out;
  if (!initialized_) {
    out.rejected = static_cast<int>(sightings.size());
    return out;
  }
  ++batches_;
  // Screen the batch: bad input, ids outside the known map in localization mode, duplicate ids in one image.
  std::vector<RangeBearing> batch;
  std::vector<int> slot;  // identified slot, -1 for the known map and sightings without id; -2 - slot: new
  std::set<int64_t> ids;
  for (const auto& s : sightings) {
    if (!valid(s)) {
      ++out.rejected;
      continue;
    }
    if (s.id >= 0 && !ids.insert(s.id).second) {
      ++out.rejected;
      continue;
    }
    int sl = -1;
    if (s.id >= 0 && !known_.count(s.id)) {
      if (auto it = identified_slot_.find(s.id); it != identified_slot_.end()) {
        sl = it->second;
      } else if (!options_.slam || static_cast<int>(identified_slot_.size()) >= options_.max_landmarks) {
        ++out.unknown;
        continue;
      } else {
        const int32_t n = static_cast<int32_t>(identified_slot_.size());
        identified_slot_[s.id] = n;
        sl = -2 - n;
      }
    }
    if (s.id < 0 && !options_.slam && known_.empty()) {
      ++out.unknown;
      continue;
    }
    batch.push_back(s);
    slot.push_back(sl);
  }
  drop_over_budget(batch, slot, out);
  if (batch.empty()) return out;
  size_t best = 0;
  for (size_t i = 1; i < particles_.size(); ++i)
    if (particles_[i].log_weight > particles_[best].log_weight) best = i;
  std::vector<char> gated_everywhere(batch.size(), 1);
  for (size_t i = 0; i < particles_.size(); ++i)
    observe_particle(particles_[i], batch, slot, gated_everywhere, i == best ? &out : nullptr);
  for (char g : gated_everywhere) out.gated += g;
  // Keep log-weights bounded, then resample if the weights have degenerated.
  double top = -INFINITY;
  for (const auto& p : particles_) top = std::max(top, p.log_weight);
  for (auto& p : particles_) p.log_weight = std::isfinite(top) ? p.log_weight - top : 0.0;
  out.effective_sample_size = effective_sample_size();
  if (out.effective_sample_size < options_.resample_threshold * static_cast<double>(particles_.size())) {
    resample();
    out.resampled = true;
  }
  return out;
}

void FastSlam::drop_over_budget(std::vector<RangeBearing>& batch, std::vector<int>& slot,
                                FastSlamBatchOutcome& out) const {
  int64_t landmarks = static_cast<int64_t>(known_.size() + identified_slot_.size());
  int64_t unidentified = 0;
  for (const Particle& p : particles_) unidentified = std::max<int64_t>(unidentified, p.unidentified.slots());
  // One sighting without id: every particle considers every landmark it holds (and each one it adds in this batch).
  const int64_t per_sighting = static_cast<int64_t>(particles_.size()) * (landmarks + unidentified + 1);
  int64_t spent = 0;
  size_t kept = 0;
  for (size_t j = 0; j < batch.size(); ++j) {
    if (batch[j].id < 0) {
      if (spent + per_sighting > options_.association_budget) {
        ++out.over_budget;
        continue;
      }
      spent += per_sighting + static_cast<int64_t>(particles_.size());  // the next one may meet this one's landmark
    }
    batch[kept] = batch[j];
    slot[kept] = slot[j];
    ++kept;
  }
  batch.resize(kept);
  slot.resize(kept);
}

// One particle's proposal over a batch, built sighting by sighting: the pose Gaussian refined by each associated
// sighting, the log-weight, the landmark updates and creations left for after the pose is sampled, and the
// landmarks already taken by a sighting of the batch.
struct FastSlam::Proposal {
  PoseGaussian g;
  double log_w = 0;
  std::vector<Pending> pending;
  std::set<std::pair<int, int64_t>> used;  // (tree: 0 known, 1 identified, 2 unidentified; id or slot)
};

void FastSlam::observe_particle(Particle& p, const std::vector<RangeBearing>& batch, const std::vector<int>& slot,
                                std::vector<char>& gated_everywhere, FastSlamBatchOutcome* stats) {
  Proposal q{p.pose, 0, {}, {}};
  const int identified_count = static_cast<int>(identified_slot_.size());
  for (size_t j = 0; j < batch.size(); ++j) {
    if (batch[j].id >= 0) {
      propose_with_id(q, p, batch[j], j, slot[j], gated_everywhere, stats);
      continue;
    }
    propose_without_id(q, p, batch[j], j, identified_count, stats);
    gated_everywhere[j] = 0;
  }
  // Sample the pose from the improved proposal, then update the landmarks' EKFs from it.
  p.pose.mean = sample(q.g);
  p.pose.covariance.setZero();
  update_particle_map(p, batch, q.pending);
  drop_stale_tentatives(p, stats);
  p.log_weight += q.log_w;
}

// A sighting with an id: its landmark created from the sampled pose when first seen, else the proposal refined by
// it (known map or identified landmark) when it passes the gate; outside the gate it weighs as a new landmark.
void FastSlam::propose_with_id(Proposal& q, const Particle& p, const RangeBearing& s, size_t j, int slot,
                               std::vector<char>& gated_everywhere, FastSlamBatchOutcome* stats) const {
  if (slot <= -2) {  // first sighting of this id: created from the sampled pose below
    q.pending.push_back({j, true, false, -2 - slot});
    gated_everywhere[j] = 0;
    if (stats) ++stats->created;
    return;
  }
  const Eigen::Vector2d z(s.range, s.bearing);
  const double log_p0 = log_new_landmark_likelihood(options_.gate, s.covariance);
  Eigen::Vector2d mean;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  if (slot < 0) {
    mean = known_.at(s.id);
  } else {
    const MapLandmark* lm = p.identified.find(slot);
    if (lm == nullptr) {  // (cannot happen: identified landmarks are created in every particle)
      q.pending.push_back({j, true, false, slot});
      gated_everywhere[j] = 0;
      return;
    }
    mean = lm->mean;
    cov = lm->covariance;
  }
  PoseGaussian trial = q.g;
  const auto step = refine_proposal(trial, mean, cov, z, s.covariance);
  if (!step || step->d2 > options_.gate) {
    q.log_w += log_p0;
    return;
  }
  q.g = trial;
  q.log_w += step->log_likelihood;
  gated_everywhere[j] = 0;
  q.used.insert(slot < 0 ? std::pair<int, int64_t>{0, s.id} : std::pair<int, int64_t>{1, slot});
  if (stats) ++stats->updated;
  if (slot >= 0) q.pending.push_back({j, false, false, slot});
}

// A sighting without id: maximum likelihood over the known map and this particle's landmarks not yet taken, inside
// the gate; when none qualifies it weighs as a new landmark and, far enough from every one (and below the map's
// size limit), becomes a tentative one.
void FastSlam::propose_without_id(Proposal& q, const Particle& p, const RangeBearing& s, size_t j, int identified_count,
                                  FastSlamBatchOutcome* stats) const {
  const Eigen::Vector2d z(s.range, s.bearing);
  const double log_p0 = log_new_landmark_likelihood(options_.gate, s.covariance);
  struct Best {
    int tree = -1;
    int64_t key = 0;
    double log_likelihood = -INFINITY;
    PoseGaussian pose;
  } best;
  double nearest_d2 = INFINITY;
  const auto consider = [&](int tree, int64_t key, const Eigen::Vector2d& mean, const Eigen::Matrix2d& cov) {
    if (q.used.count({tree, key})) return;
    PoseGaussian trial = q.g;
    const auto step = refine_proposal(trial, mean, cov, z, s.covariance);
    if (step) nearest_d2 = std::min(nearest_d2, step->d2);
    if (step && step->d2 <= options_.gate && step->log_likelihood > best.log_likelihood)
      best = {tree, key, step->log_likelihood, trial};
  };
  for (const auto& [id, l] : known_) consider(0, id, l, Eigen::Matrix2d::Zero());
  if (identified_count > 0)
    p.identified.for_each([&](int32_t k, const MapLandmark& lm) { consider(1, k, lm.mean, lm.covariance); });
  p.unidentified.for_each([&](int32_t k, const MapLandmark& lm) { consider(2, k, lm.mean, lm.covariance); });
  if (best.tree >= 0) {
    q.used.insert({best.tree, best.key});
    q.g = best.pose;
    q.log_w += best.log_likelihood;
    if (best.tree > 0) q.pending.push_back({j, false, best.tree == 2, static_cast<int32_t>(best.key)});
    if (stats) ++stats->associated;
    return;
  }
  q.log_w += log_p0;
  if (options_.slam && nearest_d2 > options_.new_landmark_gate &&
      identified_count + p.unidentified.slots() < options_.max_landmarks) {
    q.pending.push_back({j, true, true, -1});
    if (stats) ++stats->created;
  }
}

// The landmarks the batch created or updated, from the particle's sampled pose (EKF updates, Joseph form).
void FastSlam::update_particle_map(Particle& p, const std::vector<RangeBearing>& batch,
                                   const std::vector<Pending>& pending) const {
  for (const Pending& u : pending) {
    const RangeBearing& s = batch[u.sighting];
    LandmarkMapTree& tree = u.in_unidentified ? p.unidentified : p.identified;
    if (u.create) {
      MapLandmark lm = new_landmark(p.pose.mean, s);
      lm.last_seen = batches_;
      if (u.in_unidentified) {
        lm.id = kUnidentifiedIdBase + tree.slots();
        tree.push_back(lm);
      } else {
        tree.set(u.slot, lm);
      }
      continue;
    }
    MapLandmark lm = *tree.find(u.slot);
    if (update_landmark(lm, p.pose.mean, Eigen::Vector2d(s.range, s.bearing), s.covariance)) {
      ++lm.observations;
      lm.last_seen = batches_;
      tree.set(u.slot, lm);
    }
  }
}

// Tentative landmarks without id that were not confirmed in time.
void FastSlam::drop_stale_tentatives(Particle& p, FastSlamBatchOutcome* stats) const {
  if (p.unidentified.slots() == 0) return;
  std::vector<int32_t> stale;
  p.unidentified.for_each([&](int32_t k, const MapLandmark& lm) {
    if (lm.observations < options_.confirmations && batches_ - lm.last_seen > options_.tentative_lifetime)
      stale.push_back(k);
  });
  for (int32_t k : stale) p.unidentified.erase(k);
  if (stats) stats->removed += static_cast<int>(stale.size());
}

std::vector<double> FastSlam::weights() const {
  std::vector<double> lw, w;
  lw.reserve(particles_.size());
  for (const auto& p : particles_) lw.push_back(p.log_weight);
  normalize_log_weights(lw, w);
  return w;
}

double FastSlam::effective_sample_size() const { return filter::effective_sample_size(weights()); }

void FastSlam::resample() {
  const std::vector<double> w = weights();
  const double u = std::uniform_real_distribution<double>(0.0, 1.0)(rng_);
  const std::vector<int> pick = low_variance_resample(w, static_cast<int>(particles_.size()), u);
  std::vector<Particle> next;
  next.reserve(pick.size());
  for (int i : pick) {
    next.push_back(particles_[static_cast<size_t>(i)]);  // copies the tree roots only: maps are shared
    next.back().log_weight = 0;
  }
  particles_ = std::move(next);
  ++resamplings_;
}

void FastSlam::mixture(SE2* mean, Eigen::Matrix3d* covariance) const {
  if (particles_.empty()) {
    if (mean) *mean = SE2();
    if (covariance) covariance->setZero();
    return;
  }
  const std::vector<double> w = weights();
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  double c = 0, s = 0;
  for (size_t i = 0; i < particles_.size(); ++i) {
    t += w[i] * particles_[i].pose.mean.head<2>();
    c += w[i] * std::cos(particles_[i].pose.mean[2]);
    s += w[i] * std::sin(particles_[i].pose.mean[2]);
  }
  const Eigen::Vector3d m(t.x(), t.y(), std::atan2(s, c));
  if (mean) *mean = SE2(m[0], m[1], m[2]);
  if (!covariance) return;
  Eigen::Matrix3d out = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < particles_.size(); ++i) {
    Eigen::Vector3d d = particles_[i].pose.mean - m;
    d[2] = wrap_angle(d[2]);
    out += w[i] * (d * d.transpose() + particles_[i].pose.covariance);
  }
  *covariance = symmetrized(out);
}

SE2 FastSlam::mean_pose() const {
  SE2 m;
  mixture(&m, nullptr);
  return m;
}

Eigen::Matrix3d FastSlam::pose_covariance() const {
  Eigen::Matrix3d c;
  mixture(nullptr, &c);
  return c;
}

std::map<int64_t, Eigen::Vector2d> FastSlam::landmarks() const {
  std::map<int64_t, Eigen::Vector2d> out = known_;
  if (particles_.empty()) return out;
  size_t best = 0;
  for (size_t i = 1; i < particles_.size(); ++i)
    if (particles_[i].log_weight > particles_[best].log_weight) best = i;
  const Particle& p = particles_[best];
  p.identified.for_each([&](int32_t, const MapLandmark& lm) { out[lm.id] = lm.mean; });
  p.unidentified.for_each([&](int32_t, const MapLandmark& lm) {
    if (lm.observations >= options_.confirmations) out[lm.id] = lm.mean;
  });
  return out;
}

void FastSlam::save(archive::ArchiveWriter& w) const {
  w(initialized_)(static_cast<uint64_t>(particles_.size()));
  for (const Particle& p : particles_) w(p.pose.mean)(p.pose.covariance)(p.log_weight)(p.identified)(p.unidentified);
  w(known_)(std::map<int64_t, int32_t>(identified_slot_.begin(), identified_slot_.end()))(batches_)(resamplings_);
  std::ostringstream rng, normal;
  rng << rng_;
  normal << normal_;
  w(rng.str())(normal.str());
}

void FastSlam::load(archive::ArchiveReader& r) {
  r(initialized_);
  particles_.resize(r.count(1, "the particles"));
  for (Particle& p : particles_) r(p.pose.mean)(p.pose.covariance)(p.log_weight)(p.identified)(p.unidentified);
  std::map<int64_t, int32_t> slots;
  r(known_)(slots)(batches_)(resamplings_);
  identified_slot_ = std::unordered_map<int64_t, int32_t>(slots.begin(), slots.end());
  std::istringstream rng(r.get<std::string>()), normal(r.get<std::string>());
  rng >> rng_;
  normal >> normal_;
  if (rng.fail() || normal.fail()) r.fail("a particle filter whose random generator state does not read back");
}

}  // namespace sextant::filter
