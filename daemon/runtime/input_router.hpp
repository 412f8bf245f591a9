#pragma once
// The daemon's input path once a message's bytes are in: the intake decides (decode, validation, time guard), and
// what it decided reaches the stage threads.  An accepted event is offered to every stage that wants it (a full queue
// is a drop on the channel); the bodies whose odometry stream expired are forgotten by every stage; and the first
// message of a body whose clock was re-synchronised carries the order to forget that body
// (QueuedEvent::forget_first), so that each stage forgets it in order with the body's earlier messages, whatever is
// still queued: the stages' state of the old clock (a filter's last time, the graph's odometry, the last published
// pose) would refuse every message of the new one.  Called from one thread (the daemon's LCM thread).
#include "daemon/runtime/channel_stats.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/stage_runner.hpp"

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace sextant::runtime {

/// Routes one message of `channel`; true when the intake accepted it.
bool route_input(Intake& intake, const std::vector<std::unique_ptr<StageRunner>>& runners, ChannelStats& stats,
                 const std::string& channel, const void* data, size_t size,
                 std::chrono::steady_clock::time_point received);

}  // namespace sextant::runtime
