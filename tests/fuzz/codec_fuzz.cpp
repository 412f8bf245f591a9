// Fuzz harness: the message codec, every type that arrives from outside (the daemon's inputs, the fleet's two; ground truth,
// match requests, fused poses, status, trajectories and targets, which the tools decode).  The first byte picks the
// type; with its high bit set the harness writes the type's fingerprint in front of the rest, so that the fuzzer reaches the
// layout walk and the validation behind the fingerprint check (random bytes almost never carry a fingerprint).
// Contract checked: decoding never throws and never crashes; what it accepts re-encodes and decodes to the same event.
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/wire_layout.hpp"

#include <sextant/truth_t.hpp>

#include <cstdint>
#include <cstdlib>
#include <vector>

using namespace sextant;

namespace {

template <class Msg>
std::vector<uint8_t> framed(bool add_fingerprint, const uint8_t* data, size_t size) {
  std::vector<uint8_t> b;
  if (add_fingerprint) {
    b.resize(8);
    int64_t h = Msg::getHash();
    __int64_t_encode_array(b.data(), 0, 8, &h, 1);
  }
  b.insert(b.end(), data, data + size);
  return b;
}

template <class Msg>
void decode_other(bool fp, const uint8_t* data, size_t size) {
  const auto b = framed<Msg>(fp, data, size);
  Msg m;
  (void)runtime::safe_decode(b.data(), b.size(), m);
}

template <class Msg>
void decode_input(runtime::InputKind kind, bool fp, const uint8_t* data, size_t size) {
  const auto b = framed<Msg>(fp, data, size);
  const runtime::Decoded d = runtime::decode_event(kind, b.data(), b.size());
  if (const auto* e = std::get_if<engine::Event>(&d)) {
    // Accepted: the event survives a round trip through the encoder (the validated values are representable).
    std::visit(
        [&](const auto& x) {
          const auto msg = runtime::to_message(x, "fuzz", 1);
          std::vector<uint8_t> out(static_cast<size_t>(msg.getEncodedSize()));
          if (msg.encode(out.data(), 0, static_cast<int>(out.size())) < 0) std::abort();
          const runtime::Decoded again = runtime::decode_event(kind, out.data(), out.size());
          if (!std::holds_alternative<engine::Event>(again)) std::abort();
        },
        *e);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const bool fp = (data[0] & 0x80) != 0;
  const uint8_t which = data[0] & 0x7f;
  ++data, --size;
  // The fleet's two messages have picks of their own (12, 13), so the older picks keep their types.
  if (which == 12) {
    decode_input<sextant::fleet_contribution_t>(runtime::InputKind::kFleet, fp, data, size);
    return 0;
  }
  if (which == 13) {
    decode_input<sextant::fleet_control_t>(runtime::InputKind::kFleetControl, fp, data, size);
    return 0;
  }
  switch (which % 12) {
    case 0:
      decode_input<sextant::odometry_t>(runtime::InputKind::kOdometry, fp, data, size);
      break;
    case 1:
      decode_input<sextant::landmarks_t>(runtime::InputKind::kLandmarks, fp, data, size);
      break;
    case 2:
      decode_input<sextant::bearing_scan_t>(runtime::InputKind::kBearings, fp, data, size);
      break;
    case 3:
      decode_input<sextant::loop_closure_t>(runtime::InputKind::kLoopClosures, fp, data, size);
      break;
    case 4:
      decode_other<sextant::truth_t>(fp, data, size);
      break;
    case 5:
      decode_other<sextant::match_request_t>(fp, data, size);
      break;
    case 6:
      decode_other<sextant::fused_pose_t>(fp, data, size);
      break;
    case 7:
      decode_other<sextant::status_t>(fp, data, size);
      break;
    case 8:
      decode_other<sextant::trajectory_t>(fp, data, size);
      break;
    case 9:
      decode_other<sextant::targets_t>(fp, data, size);
      break;
    case 10:
      decode_input<sextant::imu_t>(runtime::InputKind::kImu, fp, data, size);
      break;
    default:
      decode_input<sextant::gnss_t>(runtime::InputKind::kGnss, fp, data, size);
      break;
  }
  return 0;
}
