#include "estimators/graph/g2o_io.hpp"

#include "estimators/graph/initialization.hpp"
#include "estimators/kind_names.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <cctype>
#include <charconv>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace sextant::graph {
namespace {

// One line's tokens, read where they lie: the line is split in place (each token's end overwritten with a NUL, so
// strtod reads it without a copy), one allocation per file rather than a string per token.
struct LineReader {
  std::string file;
  int line = 0;
  std::vector<std::string_view> tokens;  // into the current line, each followed by a NUL
  size_t next = 1;

  // The C locale's white space (what a stream's >> skips), without a call per character.
  static bool blank(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }

  // Splits `text` (changed: separators become NULs) into tokens at whitespace, as a stream's >> would.
  void split(std::string& text) {
    tokens.clear();
    next = 1;
    char* p = text.data();
    char* const end = p + text.size();
    while (true) {
      while (p < end && blank(*p)) ++p;
      if (p == end) return;
      char* const first = p;
      while (p < end && !blank(*p)) ++p;
      tokens.emplace_back(first, static_cast<size_t>(p - first));
      if (p == end) return;  // text's own terminating NUL follows
      *p++ = '\0';
    }
  }
  std::string tag() const { return std::string(tokens[0]); }
  [[noreturn]] void fail(const std::string& msg) const {
    throw std::runtime_error(file + ":" + std::to_string(line) + ": " + msg);
  }
  double number() {
    if (next >= tokens.size()) fail(tag() + ": expected more values (got " + std::to_string(tokens.size() - 1) + ")");
    const std::string_view t = tokens[next++];
    // from_chars for the plain decimals of a g2o file (correctly rounded, as strtod, and several times faster);
    // strtod, and its verdict, for the rest (a leading '+', hexadecimal, out of range).
    double v = 0;
    if (const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        ec == std::errc() && end == t.data() + t.size())
      return v;
    char* end = nullptr;
    v = std::strtod(t.data(), &end);
    if (end != t.data() + t.size()) fail(tag() + ": not a number: '" + std::string(t) + "'");
    return v;
  }
  int64_t integer() {
    const double v = number();
    // The range first: casting a double outside int64's range is undefined behaviour.
    if (!(v >= -0x1p63 && v < 0x1p63)) fail(tag() + ": id out of range: '" + std::string(tokens[next - 1]) + "'");
    if (v != static_cast<double>(static_cast<int64_t>(v)))
      fail(tag() + ": not an integer id: '" + std::string(tokens[next - 1]) + "'");
    return static_cast<int64_t>(v);
  }
  void done() const {
    if (next != tokens.size()) fail(tag() + ": " + std::to_string(tokens.size() - next) + " unexpected extra value(s)");
  }
  // The N x N information matrix from its upper triangle, row by row (fixed size: no allocation).
  template <int N>
  Eigen::Matrix<double, N, N> upper_information() {
    Eigen::Matrix<double, N, N> I;
    for (int r = 0; r < N; ++r)
      for (int c = r; c < N; ++c) I(r, c) = I(c, r) = number();
    return I;
  }
  // Several values in order (function arguments have no evaluation order, so never read inside a call).
  Eigen::VectorXd numbers(int n) {
    Eigen::VectorXd v(n);
    for (int k = 0; k < n; ++k) v[k] = number();
    return v;
  }
  Eigen::Vector3d vector3() {
    const Eigen::VectorXd v = numbers(3);
    return {v[0], v[1], v[2]};
  }
  SE2 se2() {
    const Eigen::VectorXd v = numbers(3);
    return SE2(v[0], v[1], v[2]);
  }
  Eigen::Quaterniond quaternion_xyzw() {
    const Eigen::VectorXd c = numbers(4);
    const double x = c[0], y = c[1], z = c[2], w = c[3];
    const Eigen::Quaterniond q(w, x, y, z);
    if (!(q.norm() > 1e-9)) fail(tag() + ": zero quaternion");
    return q.normalized();
  }
};

struct PendingEdge {
  int line;
  std::string tag;
  int64_t a, b;
  std::function<std::unique_ptr<Factor>(int, int)> make;
};

// Edges shown by name in the error about bad information matrices (the rest are counted).
constexpr size_t kBadEdgesShown = 5;

}  // namespace

namespace {
constexpr std::pair<InformationPolicy, const char*> kInformationPolicies[] = {
    {InformationPolicy::kReject, "reject"},
    {InformationPolicy::kRepair, "repair"},
    {InformationPolicy::kDiagonal, "diagonal"}};
}  // namespace

InformationPolicy information_policy_from_name(const std::string& name) {
  return kind_from_name(kInformationPolicies, name, "information policy");
}
const char* information_policy_name(InformationPolicy policy) { return kind_name(kInformationPolicies, policy); }
std::vector<std::string> information_policy_names() { return kind_names(kInformationPolicies); }

Eigen::MatrixXd repair_information(const Eigen::MatrixXd& I, InformationPolicy policy) {
  if (policy == InformationPolicy::kReject) return I;
  const Eigen::MatrixXd S = symmetrized(I);
  if (policy == InformationPolicy::kDiagonal) {
    const double floor = 1e-6 * std::max(S.diagonal().cwiseAbs().maxCoeff(), 1e-300);
    return S.diagonal().cwiseMax(floor).asDiagonal();
  }
  const Eigen::VectorXd eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S, Eigen::EigenvaluesOnly).eigenvalues();
  const double floor = 1e-6 * std::max(eigenvalues.cwiseAbs().maxCoeff(), 1e-300);
  return symmetrized(floor_eigenvalues(S, floor));
}

G2oGraph read_g2o(const std::string& path, const G2oReadOptions& options) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  return read_g2o(in, path, options);
}

namespace {

// One read of a g2o file: each line read into a vertex (added at once) or a pending edge (added once every vertex
// is known, so edges may come first), then the bad information matrices reported, the edges and FIX lines applied.
class G2oReader {
 public:
  G2oReader(const std::string& path, const G2oReadOptions& options)
      : path_(path), options_(options), r_{path, 0, {}, 1} {}

  G2oGraph read(std::istream& in) {
    std::string text;
    while (std::getline(in, text)) {
      ++r_.line;
      const size_t hash = text.find('#');
      if (hash != std::string::npos) text.resize(hash);
      r_.split(text);
      if (!r_.tokens.empty()) read_line();
    }
    throw_if_bad_information();
    if (saw2_ && saw3_) throw std::runtime_error(path_ + ": mixes 2-D and 3-D poses");
    out_.dimension = saw3_ ? 3 : 2;
    for (const auto& e : edges_) add_edge(e);
    apply_fixes();
    if (!out_.had_vertices) initialize_by_odometry(out_.graph);
    return std::move(out_);
  }

 private:
  // One line's tokens (a tag and its values): a vertex, an edge, a parameter or FIX.
  void read_line() {
    const std::string tag = r_.tag();
    if (tag.rfind("VERTEX_", 0) == 0) {
      const Variable v = read_vertex(tag);
      r_.done();
      if (out_.graph.index_of(v.id) >= 0) r_.fail(tag + ": vertex " + std::to_string(v.id) + " defined twice");
      out_.graph.add_variable(v);
      out_.had_vertices = true;
      return;
    }
    if (tag.rfind("EDGE_", 0) == 0)
      read_edge(tag);
    else if (tag == "PARAMS_SE3OFFSET") {
      const int64_t id = r_.integer();
      const Eigen::Vector3d t = r_.vector3();
      offsets_[id] = SE3(r_.quaternion_xyzw(), t);
    } else if (tag == "FIX") {
      while (r_.next < r_.tokens.size()) fixes_.push_back({r_.line, r_.integer()});
    } else {
      r_.fail("unknown tag '" + tag + "'");
    }
    r_.done();
  }

  Variable read_vertex(const std::string& tag) {
    Variable v;
    if (tag == "VERTEX_SE2") {
      v.kind = VariableKind::kPose2;
      v.id = r_.integer();
      v.pose2 = r_.se2();
      saw2_ = true;
    } else if (tag == "VERTEX_SE3:QUAT") {
      v.kind = VariableKind::kPose3;
      v.id = r_.integer();
      const Eigen::Vector3d t = r_.vector3();
      v.pose3 = SE3(r_.quaternion_xyzw(), t);
      saw3_ = true;
    } else if (tag == "VERTEX_XY") {
      v.kind = VariableKind::kPoint2;
      v.id = r_.integer();
      v.point << r_.numbers(2), 0;
    } else if (tag == "VERTEX_TRACKXYZ") {
      v.kind = VariableKind::kPoint3;
      v.id = r_.integer();
      v.point = r_.vector3();
    } else {
      r_.fail("unknown tag '" + tag + "'");
    }
    return v;
  }

  void read_edge(const std::string& tag) {
    if (tag == "EDGE_SE2") {
      const int64_t a = r_.integer(), b = r_.integer();
      const SE2 z = r_.se2();
      const Eigen::Matrix3d I = information(r_.upper_information<3>(), a, b);
      saw2_ = true;
      edges_.push_back(
          {r_.line, tag, a, b, [z, I](int i, int j) { return std::make_unique<RelativePoseFactor>(i, j, z, I); }});
    } else if (tag == "EDGE_SE3:QUAT") {
      const int64_t a = r_.integer(), b = r_.integer();
      const Eigen::Vector3d t = r_.vector3();
      const SE3 z(r_.quaternion_xyzw(), t);
      const Matrix6d I = information(r_.upper_information<6>(), a, b);
      saw3_ = true;
      edges_.push_back(
          {r_.line, tag, a, b, [z, I](int i, int j) { return std::make_unique<RelativePoseFactor>(i, j, z, I); }});
    } else if (tag == "EDGE_SE2_XY") {
      const int64_t a = r_.integer(), b = r_.integer();
      const Eigen::VectorXd z = r_.numbers(2);
      const Eigen::MatrixXd I = information(r_.upper_information<2>(), a, b);
      edges_.push_back({r_.line, tag, a, b, [z, I](int i, int j) {
                          return std::make_unique<PointObservationFactor>(
                              i, j, PointObservationFactor::Model::kPosition, z, I);
                        }});
    } else if (tag == "EDGE_SE3_TRACKXYZ") {
      const int64_t a = r_.integer(), b = r_.integer(), param = r_.integer();
      const Eigen::VectorXd z = r_.numbers(3);
      const Eigen::MatrixXd I = information(r_.upper_information<3>(), a, b);
      if (!offsets_.count(param))
        r_.fail("EDGE_SE3_TRACKXYZ: unknown parameter id " + std::to_string(param) +
                " (PARAMS_SE3OFFSET must come first)");
      const SE3 offset = offsets_.at(param);
      edges_.push_back({r_.line, tag, a, b, [z, I, offset](int i, int j) {
                          return std::make_unique<PointObservationFactor>(
                              i, j, PointObservationFactor::Model::kPosition, z, I, offset);
                        }});
    } else {
      r_.fail("unknown tag '" + tag + "'");
    }
  }

  // An edge's information matrix: kept when positive definite; else repaired (options.information), or listed for
  // the error about bad information matrices.
  template <int N>
  Eigen::Matrix<double, N, N> information(const Eigen::Matrix<double, N, N>& I, int64_t a, int64_t b) {
    const DefinitenessCheck check = check_positive_definite(I);
    if (check.ok()) return I;
    if (check.problem == DefinitenessCheck::Problem::kNotFinite)
      r_.fail(r_.tag() + " " + std::to_string(a) + " " + std::to_string(b) +
              ": information matrix has a NaN or infinite entry");
    if (options_.information != InformationPolicy::kReject) {
      ++out_.repaired_information;
      return repair_information(I, options_.information);  // N x N, as I
    }
    std::ostringstream m;
    m << path_ << ":" << r_.line << " (" << r_.tokens[0] << " " << a << " " << b << ", smallest eigenvalue "
      << check.smallest_eigenvalue << ")";
    bad_.push_back(m.str());
    return I;
  }

  // Every bad information matrix at once (the first kBadEdgesShown by name).
  void throw_if_bad_information() const {
    if (bad_.empty()) return;
    std::ostringstream m;
    m << path_ << ": " << bad_.size() << " edge"
      << (bad_.size() > 1 ? "s have information matrices" : " has an information matrix") << " that "
      << (bad_.size() > 1 ? "are" : "is") << " not positive definite: ";
    for (size_t i = 0; i < std::min(bad_.size(), kBadEdgesShown); ++i) m << (i ? "; " : "") << bad_[i];
    if (bad_.size() > kBadEdgesShown) m << "; and " << bad_.size() - kBadEdgesShown << " more";
    IndefiniteInformationError e(m.str());
    e.edges = static_cast<int>(bad_.size());
    throw e;
  }

  // A pending edge into the graph: its vertices (created for pose edges in a file without vertices), kinds that fit.
  void add_edge(const PendingEdge& e) {
    FactorGraph& g = out_.graph;
    int ia = g.index_of(e.a), ib = g.index_of(e.b);
    for (auto [id, idx] : {std::pair{e.a, &ia}, std::pair{e.b, &ib}}) {
      if (*idx >= 0) continue;
      if (out_.had_vertices)
        throw std::runtime_error(path_ + ":" + std::to_string(e.line) + ": " + e.tag + " refers to vertex " +
                                 std::to_string(id) + ", which is not defined");
      if (e.tag != "EDGE_SE2" && e.tag != "EDGE_SE3:QUAT")
        throw std::runtime_error(path_ + ":" + std::to_string(e.line) + ": " + e.tag + " needs its vertices defined");
      Variable v;
      v.id = id;
      v.kind = out_.dimension == 3 ? VariableKind::kPose3 : VariableKind::kPose2;
      *idx = g.add_variable(v);
    }
    if (ia == ib)
      throw std::runtime_error(path_ + ":" + std::to_string(e.line) + ": " + e.tag + " joins vertex " +
                               std::to_string(e.a) + " to itself");
    auto f = e.make(ia, ib);
    // Kinds must fit the edge.
    const auto ka = g.variables()[static_cast<size_t>(ia)].kind, kb = g.variables()[static_cast<size_t>(ib)].kind;
    const bool ok = (e.tag == "EDGE_SE2" && ka == VariableKind::kPose2 && kb == VariableKind::kPose2) ||
                    (e.tag == "EDGE_SE3:QUAT" && ka == VariableKind::kPose3 && kb == VariableKind::kPose3) ||
                    (e.tag == "EDGE_SE2_XY" && ka == VariableKind::kPose2 && kb == VariableKind::kPoint2) ||
                    (e.tag == "EDGE_SE3_TRACKXYZ" && ka == VariableKind::kPose3 && kb == VariableKind::kPoint3);
    if (!ok)
      throw std::runtime_error(path_ + ":" + std::to_string(e.line) + ": " + e.tag +
                               " between vertices of the wrong kinds");
    g.add_factor(std::move(f));
  }

  void apply_fixes() {
    for (const auto& [line, id] : fixes_) {
      const int i = out_.graph.index_of(id);
      if (i < 0)
        throw std::runtime_error(path_ + ":" + std::to_string(line) + ": FIX of unknown vertex " + std::to_string(id));
      out_.graph.variables()[static_cast<size_t>(i)].fixed = true;
    }
  }

  const std::string& path_;
  const G2oReadOptions& options_;
  LineReader r_;
  G2oGraph out_;
  std::map<int64_t, SE3> offsets_;
  std::vector<PendingEdge> edges_;
  std::vector<std::pair<int, int64_t>> fixes_;
  bool saw2_ = false, saw3_ = false;
  std::vector<std::string> bad_;  // information matrices that are not positive definite, for the error
};

}  // namespace

G2oGraph read_g2o(std::istream& in, const std::string& path, const G2oReadOptions& options) {
  return G2oReader(path, options).read(in);
}

void write_g2o(const std::string& path, const FactorGraph& g) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!f) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  const auto& vars = g.variables();
  for (const auto& v : vars) {
    switch (v.kind) {
      case VariableKind::kPose2:
        std::fprintf(f.get(), "VERTEX_SE2 %lld %.17g %.17g %.17g\n", (long long)v.id, v.pose2.translation().x(),
                     v.pose2.translation().y(), v.pose2.angle());
        break;
      case VariableKind::kPose3: {
        const auto& t = v.pose3.translation();
        const auto& q = v.pose3.rotation().quaternion();
        std::fprintf(f.get(), "VERTEX_SE3:QUAT %lld %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", (long long)v.id,
                     t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
        break;
      }
      case VariableKind::kPoint2:
        std::fprintf(f.get(), "VERTEX_XY %lld %.17g %.17g\n", (long long)v.id, v.point.x(), v.point.y());
        break;
      case VariableKind::kPoint3:
        std::fprintf(f.get(), "VERTEX_TRACKXYZ %lld %.17g %.17g %.17g\n", (long long)v.id, v.point.x(), v.point.y(),
                     v.point.z());
        break;
      case VariableKind::kVector3:
        throw std::invalid_argument("cannot write " + path + ": g2o has no vertex for the vector variable " +
                                    std::to_string(v.id) + " (a velocity or an IMU bias)");
    }
  }
  auto info = [&](const Eigen::MatrixXd& I) {
    for (int r = 0; r < I.rows(); ++r)
      for (int c = r; c < I.cols(); ++c) std::fprintf(f.get(), " %.17g", I(r, c));
    std::fprintf(f.get(), "\n");
  };
  std::vector<SE3> offsets;  // written so far; PARAMS_SE3OFFSET id = position
  auto offset_id = [&](const SE3& o) {
    for (size_t k = 0; k < offsets.size(); ++k)
      if (offsets[k].translation() == o.translation() &&
          offsets[k].rotation().quaternion().coeffs() == o.rotation().quaternion().coeffs())
        return static_cast<long long>(k);
    offsets.push_back(o);
    const auto& t = o.translation();
    const auto& q = o.rotation().quaternion();
    std::fprintf(f.get(), "PARAMS_SE3OFFSET %zu %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", offsets.size() - 1, t.x(),
                 t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    return static_cast<long long>(offsets.size() - 1);
  };
  for (const auto& fac : g.factors()) {
    const long long a = vars[static_cast<size_t>(fac->variables()[0])].id;
    if (const auto* rp = dynamic_cast<const RelativePoseFactor*>(fac.get())) {
      const long long b = vars[static_cast<size_t>(fac->variables()[1])].id;
      if (rp->planar()) {
        const auto& z = rp->measurement2();
        std::fprintf(f.get(), "EDGE_SE2 %lld %lld %.17g %.17g %.17g", a, b, z.translation().x(), z.translation().y(),
                     z.angle());
      } else {
        const auto& z = rp->measurement3();
        const auto& t = z.translation();
        const auto& q = z.rotation().quaternion();
        std::fprintf(f.get(), "EDGE_SE3:QUAT %lld %lld %.17g %.17g %.17g %.17g %.17g %.17g %.17g", a, b, t.x(), t.y(),
                     t.z(), q.x(), q.y(), q.z(), q.w());
      }
      info(fac->information());
    } else if (const auto* po = dynamic_cast<const PointObservationFactor*>(fac.get());
               po && po->model() == PointObservationFactor::Model::kPosition) {
      const long long b = vars[static_cast<size_t>(fac->variables()[1])].id;
      const auto& z = po->measurement();
      if (z.size() == 2) {
        std::fprintf(f.get(), "EDGE_SE2_XY %lld %lld %.17g %.17g", a, b, z[0], z[1]);
      } else {
        const long long param = offset_id(po->sensor_offset());
        std::fprintf(f.get(), "EDGE_SE3_TRACKXYZ %lld %lld %lld %.17g %.17g %.17g", a, b, param, z[0], z[1], z[2]);
      }
      info(fac->information());
    }
  }
  for (const auto& v : vars)
    if (v.fixed) std::fprintf(f.get(), "FIX %lld\n", (long long)v.id);
}

}  // namespace sextant::graph
