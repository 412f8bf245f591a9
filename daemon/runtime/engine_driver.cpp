#include "daemon/runtime/engine_driver.hpp"

#include "daemon/engine/graph_stage.hpp"
#include "daemon/runtime/codec.hpp"

#include <algorithm>

namespace sextant::runtime {
namespace {

// The graph stage's odometry is batched per body on its thread (engine.graph.coalesce_odometry): the stage keeps
// each body's state apart, so batching (which keeps each body's order but not the order across bodies) changes
// nothing it computes.  The other stages see every message in arrival order (a filter may fuse several sources of
// one body).
std::optional<OdometryBatcherOptions> odometry_batching(const engine::Stage& stage,
                                                        const engine::EngineConfig& config) {
  if (stage.kind() != engine::StageKind::kGraph || !config.graph.coalesce_odometry) return std::nullopt;
  OdometryBatcherOptions o;
  o.max_batch = static_cast<size_t>(config.graph.odometry_batch_max);
  o.max_waiting_per_body = static_cast<size_t>(config.graph.odometry_waiting_max);
  o.max_waiting = static_cast<size_t>(config.graph.odometry_waiting_total_max);
  return o;
}

}  // namespace

EngineDriver::EngineDriver(const config::DaemonConfig& config, engine::Engine& engine, Publisher::RawSink raw,
                           DriverOptions options)
    : engine_(engine),
      options_(std::move(options)),
      intake_(stats_, options_.on_reject, intake_options(config, options_.live)),
      // The last FusedPose time per estimator channel and body: the bodies are bounded by max_sources.
      publisher_(config.channels, config.name, engine.primary_estimator(), std::move(raw),
                 static_cast<size_t>(std::max(config.max_sources, 1)) * 8),
      emit_([this](engine::Output o) { publish(std::move(o)); }) {
  const auto& ch = config.channels;
  intake_.add_channel(ch.full(ch.odometry), InputKind::kOdometry);
  intake_.add_channel(ch.full(ch.landmarks), InputKind::kLandmarks);
  intake_.add_channel(ch.full(ch.bearings), InputKind::kBearings);
  intake_.add_channel(ch.full(ch.loop_closures), InputKind::kLoopClosures);
  intake_.add_channel(ch.full(ch.imu), InputKind::kImu);
  intake_.add_channel(ch.full(ch.gnss), InputKind::kGnss);
  // The fleet's channels are shared by its daemons: no prefix (daemon_config.hpp).
  if (config.engine.graph.enabled && config.engine.graph.fleet_exchange.enabled) {
    intake_.add_channel(ch.fleet, InputKind::kFleet);
    intake_.add_channel(ch.fleet_control, InputKind::kFleetControl);
    tick_channel_ = ch.fleet_control;
  }
  // The fleet exchange numbers no local contribution that the other members' decoders would refuse.
  for (auto& stage : engine_.stages())
    if (auto* graph = dynamic_cast<engine::GraphStage*>(stage.get())) graph->set_fleet_wire_check(fleet_item_error);
  make_lanes(config);
}

EngineDriver::~EngineDriver() {
  for (auto& r : runners_) r->drain_and_stop();
}

void EngineDriver::make_lanes(const config::DaemonConfig& config) {
  for (auto& stage : engine_.stages()) estimators_.emplace_back(stage->estimator());
  if (options_.lanes == StageLanes::kPipelined) make_pipelined_lanes();
  for (size_t i = 0; i < engine_.stages().size(); ++i) {
    engine::Stage& stage = *engine_.stages()[i];
    // A body the stage forgets is forgotten by the publisher for the stage's estimator too, after its earlier outputs
    // (kPipelined: captured in order with the outputs, and done when they are delivered).
    StageHost::ForgetHook forget_published;
    if (pipelined_)
      forget_published = pipelined_->forgot_into(i);
    else if (!estimators_[i].empty())
      forget_published = [this, i](const std::string& body) { publisher_.forget(estimators_[i], body); };
    if (options_.lanes == StageLanes::kStageThreads) {
      runners_.push_back(std::make_unique<StageRunner>(stage, static_cast<size_t>(config.queue_capacity), emit_,
                                                       odometry_batching(stage, config.engine)));
      runners_.back()->on_forget(std::move(forget_published));
      continue;
    }
    hosts_.push_back(std::make_unique<StageHost>(stage, pipelined_ ? pipelined_->emit_into(i) : emit_));
    hosts_.back()->on_forget(std::move(forget_published));
    processed_.push_back(0);
  }
  if (!pipelined_) return;
  std::vector<StageHost*> hosts;
  for (auto& h : hosts_) hosts.push_back(h.get());
  pipelined_->attach(std::move(hosts));
}

void EngineDriver::make_pipelined_lanes() {
  // The graph pose stage reads the corrections the graph stage posts: the two share the worker.
  std::vector<char> on_worker;
  for (const auto& stage : engine_.stages())
    on_worker.push_back(stage->kind() == engine::StageKind::kGraph || stage->kind() == engine::StageKind::kGraphPose);
  const auto workers = std::count(on_worker.begin(), on_worker.end(), 1);
  if (workers == 0 || workers == static_cast<std::ptrdiff_t>(on_worker.size())) {
    options_.lanes = StageLanes::kInline;
    return;
  }
  pipelined_ = std::make_unique<PipelinedLanes>(on_worker, [this](StageCapture& c) { deliver(c); });
}

void EngineDriver::deliver(StageCapture& c) {
  if (auto* output = std::get_if<engine::Output>(&c.what)) {
    publish(std::move(*output));
  } else if (auto* forgot = std::get_if<StageCapture::Forgot>(&c.what)) {
    if (!estimators_[c.stage].empty()) publisher_.forget(estimators_[c.stage], forgot->body);
  } else {
    ++processed_[c.stage];
    if (options_.on_handled) options_.on_handled(c.stage, std::get<StageCapture::Handled>(c.what).ms);
  }
}

void EngineDriver::publish(engine::Output output) {
  if (options_.zero_solve_time)
    if (auto* t = std::get_if<engine::Trajectory>(&output)) t->solve_ms = 0;
  if (publisher_.publish(output) && options_.on_published) options_.on_published(output);
}

void EngineDriver::forget_expired() {
  for (const std::string& body : intake_.take_expired_bodies()) {
    if (pipelined_) {
      pipelined_->forget_before_next(body);
      continue;
    }
    for (auto& h : hosts_) h->forget(body);
    for (auto& r : runners_) r->forget(body);
  }
}

void EngineDriver::route(const std::string& channel, QueuedEvent queued) {
  if (pipelined_) return pipelined_->route(std::move(queued));
  for (size_t i = 0; i < hosts_.size(); ++i) {
    if (!hosts_[i]->stage().accepts(queued.event)) continue;
    const auto t0 = std::chrono::steady_clock::now();
    hosts_[i]->handle(queued);
    ++processed_[i];
    if (options_.on_handled)
      options_.on_handled(i, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  for (auto& r : runners_)
    if (r->accepts(queued.event) && !r->offer(queued)) stats_.dropped(channel);
}

bool EngineDriver::input(const std::string& channel, const void* data, size_t size, Arrival arrival) {
  auto event = intake_.accept(channel, data, size, arrival);
  forget_expired();
  if (!event) return false;
  if (options_.on_accepted) options_.on_accepted(*event);
  route(channel, QueuedEvent{std::move(*event), std::chrono::steady_clock::now(), intake_.resynced_body()});
  return true;
}

void EngineDriver::tick(Arrival arrival) {
  if (tick_channel_.empty()) return;
  engine::FleetControl tick;  // no sender: the clock only (GraphStage::exchange)
  tick.utime = arrival.wall_utime;
  route(tick_channel_, QueuedEvent{engine::Event(std::move(tick)), arrival.steady, {}});
}

void EngineDriver::start() {
  for (auto& r : runners_) r->start();
}

void EngineDriver::settle() {
  if (pipelined_) pipelined_->settle();
}

int64_t EngineDriver::finish(std::chrono::steady_clock::time_point deadline) {
  if (pipelined_)
    pipelined_->finish();
  else
    for (auto& h : hosts_) h->finish();
  for (auto& r : runners_) r->stop_intake();
  int64_t discarded = 0;
  for (auto& r : runners_) discarded += r->drain_and_stop(deadline);
  return discarded;
}

std::vector<StageStatus> EngineDriver::stage_status() {
  std::vector<StageStatus> all;
  for (const auto& r : runners_) all.push_back(r->status());
  for (size_t i = 0; i < hosts_.size(); ++i) {
    StageStatus s;
    s.name = std::string(hosts_[i]->stage().name());
    s.processed = processed_[i];
    s.counters = hosts_[i]->with_host_counters(hosts_[i]->stage_counters().value_or(engine::Counters{}));
    s.last_failure = hosts_[i]->last_failure();
    all.push_back(std::move(s));
  }
  return all;
}

}  // namespace sextant::runtime
