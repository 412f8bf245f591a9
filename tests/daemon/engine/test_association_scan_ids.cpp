// Scan ids are one numbering shared by every bearing sensor: one hostile scan numbered far from the others must not
// make every later scan "late", whether it is associated at once (expected_sensors), at the end of input (finish at
// shutdown) or carried through a saved state; a true renumbering is followed after a run of scans that agree on it.
#include "daemon/engine/association_stage.hpp"
#include "daemon/stage_counters.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <set>

using namespace sextant;
using namespace sextant::engine;

using sextant::stage_counters::counter;

namespace {

// Sensor k of three around a target at the origin, seeing it once.
BearingScan scan_of(int sensor, int64_t scan_id) {
  BearingScan s;
  s.utime = 1000000 + 100000 * (scan_id % 100000);
  s.sensor_id = sensor;
  const double angle = 2.0 * sensor;
  s.sensor_position = Eigen::Vector3d(10 * std::cos(angle), 10 * std::sin(angle), 0);
  s.scan_id = scan_id;
  BearingDetection d;
  d.azimuth = std::atan2(-s.sensor_position.y(), -s.sensor_position.x());
  d.elevation = 0;
  d.sigma_azimuth = d.sigma_elevation = 1e-3;
  s.detections.push_back(d);
  return s;
}

struct Sink {
  std::set<int64_t> scan_ids;  // of the emitted targets
  Emit emit() {
    return [this](Output o) {
      if (const auto* t = std::get_if<Targets>(&o)) scan_ids.insert(t->scan_id);
    };
  }
  bool has_all(int64_t from, int64_t to) const {
    for (int64_t i = from; i <= to; ++i)
      if (!scan_ids.count(i)) return false;
    return true;
  }
};

void feed(AssociationStage& stage, int64_t from, int64_t to, const Emit& emit) {
  for (int64_t id = from; id <= to; ++id)
    for (int sensor = 1; sensor <= 3; ++sensor) stage.handle(scan_of(sensor, id), emit);
}

}  // namespace

TEST_CASE("association: one scan numbered INT64_MAX blocks no later scan, through finish and a saved state") {
  AssociationConfig config;  // expected_sensors 0: a group is associated when a newer scan id arrives
  AssociationStage stage(config);
  Sink out;
  feed(stage, 1, 10, out.emit());
  stage.handle(scan_of(99, std::numeric_limits<int64_t>::max()), out.emit());  // a new sensor name, a valid utime
  feed(stage, 11, 20, out.emit());
  CHECK(out.has_all(1, 19));
  stage.finish(out.emit());  // shutdown: what is pending is associated
  CHECK(out.has_all(1, 20));
  CHECK(counter(stage, "scan_id_jumps") == 1);
  // The daemon saves its state after finish and resumes from it: later scans are associated again.
  archive::ArchiveWriter w;
  stage.save(w);
  AssociationStage resumed(config);
  archive::ArchiveReader r(w.data().data(), w.data().size(), "test");
  resumed.load(r);
  feed(resumed, 21, 30, out.emit());
  resumed.finish(out.emit());
  CHECK(out.has_all(21, 30));
  CHECK(counter(resumed, "late_scans") == 0);
}

TEST_CASE("association: a far scan id from new sensors is refused even when enough sensors report it at once") {
  AssociationConfig config;
  config.expected_sensors = 3;  // a group is associated as soon as 3 sensors reported
  AssociationStage stage(config);
  Sink out;
  feed(stage, 1, 5, out.emit());
  CHECK(out.has_all(1, 5));
  for (int sensor = 97; sensor <= 99; ++sensor) stage.handle(scan_of(sensor, 1000000), out.emit());
  feed(stage, 6, 10, out.emit());
  CHECK(out.scan_ids.count(1000000) == 0);
  CHECK(out.has_all(6, 10));
  CHECK(counter(stage, "scan_id_jumps") == 3);
  CHECK(counter(stage, "late_scans") == 0);
}

TEST_CASE("association: a true renumbering, backwards or forwards, is followed after scan_id_resync_after scans") {
  AssociationConfig config;
  config.max_scan_id_jump = 100;
  config.scan_id_resync_after = 5;
  AssociationStage stage(config);
  Sink out;
  feed(stage, 1000, 1010, out.emit());
  // The sensors restart their numbering at 0: ids 0 (3 scans) and the first of id 1 are refused, the fifth is taken.
  feed(stage, 0, 10, out.emit());
  CHECK(counter(stage, "scan_id_jumps") == 4);
  CHECK(counter(stage, "scan_id_resyncs") == 1);
  CHECK(out.has_all(1000, 1010));  // the old numbering's last group was associated at the renumbering
  CHECK(out.scan_ids.count(0) == 0);
  CHECK(out.has_all(1, 9));
  CHECK(counter(stage, "late_scans") == 0);
  // And forwards.
  feed(stage, 5000, 5010, out.emit());
  CHECK(counter(stage, "scan_id_resyncs") == 2);
  CHECK(out.has_all(10, 10));
  CHECK(out.has_all(5001, 5009));
  // 0 turns the check off: any numbering is taken as it comes.
  config.max_scan_id_jump = 0;
  AssociationStage unchecked(config);
  Sink all;
  feed(unchecked, 1, 3, all.emit());
  feed(unchecked, 1000000, 1000002, all.emit());
  CHECK(all.has_all(1, 3));
  CHECK(all.has_all(1000000, 1000001));
  CHECK(counter(unchecked, "scan_id_jumps") == 0);
}
