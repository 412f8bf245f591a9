#include "estimators/graph/graph_archive.hpp"

#include "estimators/lie/lie_archive.hpp"

#include <stdexcept>

namespace sextant::graph {
namespace {

enum class FactorTag : uint8_t { kRelativePose2 = 1, kRelativePose3 = 2, kPointObservation = 3, kPoseObservation = 4 };

}  // namespace

void save(archive::ArchiveWriter& w, const Variable& v) {
  w(v.id)(v.kind)(v.fixed);
  switch (v.kind) {
    case VariableKind::kPose2:
      w(v.pose2);
      break;
    case VariableKind::kPose3:
      w(v.pose3);
      break;
    case VariableKind::kPoint2:
    case VariableKind::kPoint3:
    case VariableKind::kVector3:
      w(v.point);
      break;
  }
}

void load(archive::ArchiveReader& r, Variable& v) {
  v = Variable{};
  r(v.id)(v.kind)(v.fixed);
  switch (v.kind) {
    case VariableKind::kPose2:
      r(v.pose2);
      break;
    case VariableKind::kPose3:
      r(v.pose3);
      break;
    case VariableKind::kPoint2:
    case VariableKind::kPoint3:
    case VariableKind::kVector3:
      r(v.point);
      break;
    default:
      r.fail("a variable of unknown kind " + std::to_string(static_cast<int>(v.kind)));
  }
}

void save_factor(archive::ArchiveWriter& w, const Factor& f) {
  if (const auto* p = dynamic_cast<const RelativePoseFactor*>(&f)) {
    w(p->planar() ? FactorTag::kRelativePose2 : FactorTag::kRelativePose3)(f.variables())(f.information());
    if (p->planar())
      w(p->measurement2());
    else
      w(p->measurement3());
  } else if (const auto* o = dynamic_cast<const PointObservationFactor*>(&f)) {
    w(FactorTag::kPointObservation)(f.variables())(f.information())(o->model())(o->measurement())(o->sensor_offset());
  } else if (const auto* o = dynamic_cast<const PoseObservationFactor*>(&f)) {
    w(FactorTag::kPoseObservation)(f.variables())(f.information())(o->model())(o->measurement())(o->sensor_offset());
    w(o->marker());
  } else {
    throw std::invalid_argument("a factor of type " + f.type() + " cannot be saved");
  }
}

std::unique_ptr<Factor> load_factor(archive::ArchiveReader& r) {
  const auto tag = r.get<FactorTag>();
  const auto vars = r.get<std::vector<int>>();
  const auto information = r.get<Eigen::MatrixXd>();
  const bool known = tag == FactorTag::kRelativePose2 || tag == FactorTag::kRelativePose3 ||
                     tag == FactorTag::kPointObservation || tag == FactorTag::kPoseObservation;
  const size_t arity = known ? 2 : 0;
  if (arity == 0) r.fail("a factor of unknown type " + std::to_string(static_cast<int>(tag)));
  if (vars.size() != arity) r.fail("a factor with " + std::to_string(vars.size()) + " variables");
  switch (tag) {
    case FactorTag::kRelativePose2: {
      if (information.rows() != 3 || information.cols() != 3)
        r.fail("a planar relative pose with a non-3x3 information");
      const SE2 z = r.get<SE2>();
      return std::make_unique<RelativePoseFactor>(vars[0], vars[1], z, Eigen::Matrix3d(information));
    }
    case FactorTag::kRelativePose3: {
      if (information.rows() != 6 || information.cols() != 6) r.fail("a 3-D relative pose with a non-6x6 information");
      const SE3 z = r.get<SE3>();
      return std::make_unique<RelativePoseFactor>(vars[0], vars[1], z, Matrix6d(information));
    }
    case FactorTag::kPointObservation:
    case FactorTag::kPoseObservation: {
      const auto model = r.get<PointObservationFactor::Model>();
      if (static_cast<int>(model) < 0 ||
          static_cast<int>(model) > static_cast<int>(PointObservationFactor::Model::kBearing))
        r.fail("a point observation of unknown model");
      const auto z = r.get<Eigen::VectorXd>();
      const SE3 offset = r.get<SE3>();
      if (information.rows() != z.size() || information.cols() != z.size())
        r.fail("a point observation whose information does not match its measurement");
      if (tag == FactorTag::kPointObservation)
        return std::make_unique<PointObservationFactor>(vars[0], vars[1], model, z, information, offset);
      const auto marker = r.get<Eigen::Vector3d>();
      if (!marker.allFinite()) r.fail("a pose observation with a non-finite marker");
      return std::make_unique<PoseObservationFactor>(vars[0], vars[1], model, z, information, offset, marker);
    }
  }
  r.fail("a factor of unknown type");
}

}  // namespace sextant::graph
