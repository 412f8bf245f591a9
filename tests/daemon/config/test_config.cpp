// Config parsing: defaults, overrides, and every error naming its file:line.
#include "assoc/chi_square.hpp"
#include "daemon/config/config_reader.hpp"
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/engine.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/graph_stage_config.hpp"

#include "config_error_of.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <sys/stat.h>
#include <unistd.h>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

using sextant::config::ConfigError;
using sextant::config::parse_daemon_config;

namespace {
const auto error_of = sextant::test::config_error_of;
}  // namespace

TEST_CASE("the shipped configs parse: default enables dead reckoning, mrclam fits the data set") {
  CHECK(sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/mrclam.yaml").queue_capacity ==
        4096);
  const auto c = sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  CHECK(c.name == "sextantd");
  CHECK(c.channels.odometry == "ODOMETRY");
  CHECK(c.channels.status == "SEXTANT_STATUS");
  CHECK(c.engine.dead_reckoning.enabled);
  CHECK(c.queue_capacity == 1024);
}

TEST_CASE("an empty file gives every default") {
  const auto c = parse_daemon_config("", "empty.yaml");
  CHECK(c.status_period_s == doctest::Approx(1.0));
  CHECK(c.channels.fused_pose == "FUSED_POSE");
  CHECK(c.channels.full("FUSED_POSE") == "FUSED_POSE");
}

TEST_CASE("values override defaults and the prefix applies to every channel") {
  const auto c =
      parse_daemon_config("daemon:\n  queue_capacity: 7\nchannels:\n  prefix: ROBOT1_\n  odometry: WHEEL\n", "t");
  CHECK(c.queue_capacity == 7);
  CHECK(c.channels.full(c.channels.odometry) == "ROBOT1_WHEEL");
}

TEST_CASE("an unknown key names its line and column") {
  const std::string e = error_of("daemon:\n  name: x\n  queue_capacty: 5\n");
  CHECK(e.find("test.yaml:3:3:") == 0);
  CHECK(e.find("unknown key 'daemon.queue_capacty'") != std::string::npos);
  CHECK(e.find("queue_capacity") != std::string::npos);  // lists the known keys
}

TEST_CASE("an unknown top-level section is an error") {
  CHECK(error_of("deamon:\n  name: x\n").find("test.yaml:1:1: unknown key 'deamon'") == 0);
}

TEST_CASE("a value of the wrong type names its line") {
  const std::string e = error_of("daemon:\n  status_period_s: often\n");
  CHECK(e.find("test.yaml:2:20:") == 0);
  CHECK(e.find("expected a number") != std::string::npos);
}

TEST_CASE("a value out of range names its line and the bound") {
  const std::string e = error_of("\n\ndaemon:\n  queue_capacity: 0\n");
  CHECK(e.find("test.yaml:4:19:") == 0);
  CHECK(e.find("must be in [1,") != std::string::npos);
}

TEST_CASE("enumerations list the allowed values") {
  const std::string e = error_of("engine:\n  primary_estimator: kalman\n");
  CHECK(e.find("test.yaml:2:22:") == 0);
  CHECK(e.find("'engine.primary_estimator': unknown estimator 'kalman' (auto, dead_reckoning, ekf, pf, graph, "
               "inertial or inertial_graph)") != std::string::npos);
}

TEST_CASE("engine.inertial.graph: its keys reach the config, out-of-range values and unknown keys name their line") {
  const auto none = parse_daemon_config("", "t").engine.inertial.graph;
  CHECK_FALSE(none.enabled);
  CHECK(none.window == 20);
  const auto set = parse_daemon_config(
                       "engine:\n  inertial:\n    graph:\n      enabled: true\n      keyframe_interval: 0.25\n"
                       "      window: 8\n      gnss_kernel_width: 3\n      initial_yaw_sigma: 1.5\n",
                       "t")
                       .engine.inertial.graph;
  CHECK(set.enabled);
  CHECK(set.keyframe_interval == 0.25);
  CHECK(set.window == 8);
  CHECK(set.gnss_kernel_width == 3);
  CHECK(set.initial_yaw_sigma == 1.5);
  CHECK(error_of("engine:\n  inertial:\n    graph:\n      window: 1\n").find("test.yaml:4:15:") == 0);
  const std::string unknown = error_of("engine:\n  inertial:\n    graph:\n      windw: 5\n");
  CHECK(unknown.find("test.yaml:4:7:") == 0);
  CHECK(unknown.find("windw") != std::string::npos);
}

TEST_CASE("engine.inertial.gnss_heading: its keys reach the config, a bad value names its line") {
  using Align = sextant::engine::GnssHeadingConfig::Align;
  const auto none = parse_daemon_config("", "t").engine.inertial.gnss_heading;
  CHECK(none.align == Align::kAuto);
  CHECK(none.baseline_m == 20);
  const auto set = parse_daemon_config(
                       "engine:\n  inertial:\n    gnss_heading:\n      align: always\n"
                       "      baseline_m: 35\n      min_inlier_fraction: 0.8\n      reacquire_after: 0\n",
                       "t")
                       .engine.inertial.gnss_heading;
  CHECK(set.align == Align::kAlways);
  CHECK(set.baseline_m == 35);
  CHECK(set.min_inlier_fraction == 0.8);
  CHECK(set.reacquire_after == 0);
  CHECK(none.reacquire_after == 10);
  CHECK(parse_daemon_config("engine:\n  inertial:\n    gnss_heading:\n      align: never\n", "t")
            .engine.inertial.gnss_heading.align == Align::kNever);
  const std::string bad = error_of("engine:\n  inertial:\n    gnss_heading:\n      align: compass\n");
  CHECK(bad.find("test.yaml:4:14:") == 0);
  CHECK(bad.find("compass") != std::string::npos);
  CHECK(error_of("engine:\n  inertial:\n    gnss_heading:\n      baseline_m: 0\n").find("test.yaml:4:19:") == 0);
}

TEST_CASE("kinds are parsed once into enums: every spelling maps to its kind, an unknown name names its file:line") {
  using sextant::engine::AssociationSolver;
  using sextant::engine::FilterType;
  CHECK(parse_daemon_config("", "t").engine.filter.type == FilterType::kEkf);
  CHECK(parse_daemon_config("engine:\n  filter:\n    type: pf\n", "t").engine.filter.type == FilterType::kPf);
  CHECK(parse_daemon_config("engine:\n  filter:\n    type: none\n", "t").engine.filter.type == FilterType::kNone);
  CHECK(parse_daemon_config("", "t").engine.association.solver == AssociationSolver::kLagrangian);
  CHECK(parse_daemon_config("engine:\n  association:\n    solver: exact\n", "t").engine.association.solver ==
        AssociationSolver::kExact);
  // Round trips through the names, and the names are the YAML spellings.
  for (auto t : {FilterType::kEkf, FilterType::kPf, FilterType::kNone})
    CHECK(sextant::engine::filter_type_from_name(sextant::engine::filter_type_name(t)) == t);
  for (auto a : {AssociationSolver::kLagrangian, AssociationSolver::kExact})
    CHECK(sextant::engine::association_solver_from_name(sextant::engine::association_solver_name(a)) == a);
  CHECK(std::string(sextant::engine::filter_type_name(FilterType::kPf)) == "pf");
  CHECK(std::string(sextant::engine::association_solver_name(AssociationSolver::kLagrangian)) == "lr");
  using sextant::engine::PrimaryEstimator;
  for (auto e : {PrimaryEstimator::kAuto, PrimaryEstimator::kDeadReckoning, PrimaryEstimator::kEkf,
                 PrimaryEstimator::kPf, PrimaryEstimator::kGraph})
    CHECK(sextant::engine::primary_estimator_from_name(sextant::engine::primary_estimator_name(e)) == e);
  CHECK(parse_daemon_config("engine:\n  primary_estimator: dead_reckoning\n", "t").engine.primary_estimator ==
        PrimaryEstimator::kDeadReckoning);
  // The spellings are the stages' estimator names: the chosen one is what goes on FUSED_POSE.
  auto cfg = parse_daemon_config("engine:\n  primary_estimator: graph\n", "t").engine;
  CHECK(sextant::engine::Engine(cfg).primary_estimator() == "graph");
  cfg.primary_estimator = PrimaryEstimator::kDeadReckoning;
  CHECK(sextant::engine::Engine(cfg).primary_estimator() == "dead_reckoning");
  cfg.primary_estimator = PrimaryEstimator::kPf;  // its stage does not run (filter type ekf): auto, the graph
  CHECK(sextant::engine::Engine(cfg).primary_estimator() == "graph");
  // Each stage's kind spells its name on the status channel, its estimator kind the FusedPose estimator name.
  cfg.dead_reckoning.enabled = cfg.graph.enabled = cfg.association.enabled = true;
  cfg.filter.type = FilterType::kPf;
  const sextant::engine::Engine all(cfg);
  std::vector<std::string> names, estimators;
  for (const auto& stage : all.stages()) names.emplace_back(stage->name()), estimators.emplace_back(stage->estimator());
  CHECK(names == std::vector<std::string>{"dead_reckoning", "particle_filter", "graph", "graph_pose", "association"});
  CHECK(estimators == std::vector<std::string>{"dead_reckoning", "pf", "", "graph", ""});
  CHECK(all.primary_estimator() == "pf");

  // Unknown names: the file, line and column of the value, the key, the name and the spellings.
  const std::string f = error_of("engine:\n  filter:\n    type: EKF\n");
  CHECK(f.find("test.yaml:3:11:") == 0);
  CHECK(f.find("'engine.filter.type': unknown filter type 'EKF' (ekf, pf or none)") != std::string::npos);
  const std::string a = error_of("engine:\n  association:\n\n    solver: lagrangian\n");
  CHECK(a.find("test.yaml:4:13:") == 0);
  CHECK(a.find("'engine.association.solver': unknown association solver 'lagrangian' (lr or exact)") !=
        std::string::npos);
  const std::string r = error_of("engine:\n  graph:\n    loops: {robust: DCS}\n");
  CHECK(r.find("test.yaml:3:21:") == 0);
  CHECK(r.find("'engine.graph.loops.robust': unknown robust kernel 'DCS' (none, huber, cauchy or dcs)") !=
        std::string::npos);
  const std::string c = error_of("engine:\n  association:\n    cost: kullback\n");
  CHECK(c.find("test.yaml:3:11:") == 0);
  CHECK(c.find("'engine.association.cost': unknown cost 'kullback' (classic, kl or renyi)") != std::string::npos);
  // Parsed once into their kinds.
  CHECK(parse_daemon_config("engine:\n  graph:\n    loops: {robust: cauchy}\n", "t").engine.graph.robust ==
        sextant::graph::RobustKernel::kCauchy);
  CHECK(parse_daemon_config("engine:\n  association:\n    cost: renyi\n", "t").engine.association.cost ==
        sextant::assoc::CostKind::kRenyi);
  // A name that is not a string is refused as such, at its line.
  CHECK(error_of("engine:\n  filter:\n    type: [ekf]\n").find("test.yaml:3:11:") == 0);
  CHECK_THROWS_AS(sextant::engine::filter_type_from_name("kalman"), std::invalid_argument);
}

TEST_CASE("a bad channel name is refused") {
  CHECK(error_of("channels:\n  odometry: \"ODO METRY\"\n").find("test.yaml:2:13:") == 0);
}

TEST_CASE("YAML syntax errors name the line") {
  const std::string e = error_of("daemon:\n  name: [unclosed\n");
  CHECK(e.find("test.yaml:") == 0);
  CHECK(e.find("YAML syntax error") != std::string::npos);
}

TEST_CASE("a section that is not a mapping is refused") {
  CHECK(error_of("daemon: 5\n").find("test.yaml:1:9: 'daemon': expected a mapping") == 0);
}

TEST_CASE("a missing file is a config error naming the path") {
  CHECK_THROWS_WITH_AS(sextant::config::load_daemon_config("/nonexistent/x.yaml"),
                       "/nonexistent/x.yaml: cannot open config file", ConfigError);
}

TEST_CASE("the loops' kernel width: auto by default (a chi-square quantile of the loop's dimension), or a number") {
  using sextant::engine::kernel_width_for;
  // Defaults: DCS, gate probability 0.999.  The width is the loop gate's quantile (assoc::chi2_quantile, exact):
  // the tables' 3 dof 16.266, 6 dof 22.458.
  const auto d = parse_daemon_config("", "t").engine.graph;
  CHECK_FALSE(d.kernel_width.has_value());
  CHECK(kernel_width_for(d, true) == sextant::assoc::chi2_quantile(3, 0.999));
  CHECK(kernel_width_for(d, false) == sextant::assoc::chi2_quantile(6, 0.999));
  CHECK(kernel_width_for(d, true) == doctest::Approx(16.266).epsilon(1e-4));
  CHECK(kernel_width_for(d, false) == doctest::Approx(22.458).epsilon(1e-4));
  // The shipped default config says auto too.
  const auto shipped = sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  CHECK_FALSE(shipped.engine.graph.kernel_width.has_value());
  // Huber's and Cauchy's delta act on sqrt(chi2): the square root of the same quantile; at 0.99, 6 dof: 16.812.
  const auto huber =
      parse_daemon_config("engine:\n  graph:\n    loops: {robust: huber, gate_probability: 0.99}\n", "t").engine.graph;
  CHECK(kernel_width_for(huber, false) == doctest::Approx(std::sqrt(sextant::assoc::chi2_quantile(6, 0.99))));
  CHECK(kernel_width_for(huber, false) == doctest::Approx(std::sqrt(16.812)).epsilon(0.01));
  // A number applies to both kinds of body; "auto" spelled out is the default.
  const auto five = parse_daemon_config("engine:\n  graph:\n    loops: {kernel_width: 5}\n", "t").engine.graph;
  CHECK(kernel_width_for(five, true) == 5.0);
  CHECK(kernel_width_for(five, false) == 5.0);
  CHECK_FALSE(
      parse_daemon_config("engine:\n  graph:\n    loops: {kernel_width: auto}\n", "t").engine.graph.kernel_width);
  // Anything else names its place.
  for (const char* bad : {"wide", "-1", "0", "1e400", "5m"}) {
    const std::string e = error_of(std::string("engine:\n  graph:\n    loops:\n      kernel_width: ") + bad + "\n");
    CHECK(e.find("test.yaml:4:21:") == 0);
    CHECK(e.find("expected 'auto' or a positive number") != std::string::npos);
  }
}

namespace {
// The options the graph stage gives its planar smoother (created with the first planar body's first odometry).
sextant::graph::IncrementalOptions planar_smoother_options(const sextant::engine::GraphConfig& config) {
  sextant::engine::GraphStage stage(config, std::make_shared<sextant::engine::GraphCorrections>());
  sextant::engine::Odometry o;
  o.utime = 1'000'000;
  o.source = "robot";
  o.planar = true;
  stage.handle(o, [](sextant::engine::Output) {});
  REQUIRE(stage.smoother(true) != nullptr);
  return stage.smoother(true)->options();
}

// The keys of engine.graph.smoother and the IncrementalOptions field each one sets.
void check_smoother_options(const sextant::graph::IncrementalOptions& got,
                            const sextant::graph::IncrementalOptions& want) {
  CHECK(got.relinearize_translation == want.relinearize_translation);
  CHECK(got.relinearize_rotation == want.relinearize_rotation);
  CHECK(got.relinearization_passes == want.relinearization_passes);
  CHECK(got.relinearize_skip == want.relinearize_skip);
  CHECK(got.wildfire == want.wildfire);
  CHECK(got.update_fraction == want.update_fraction);
  CHECK(got.min_update_factors == want.min_update_factors);
  CHECK(got.max_update_factors == want.max_update_factors);
  CHECK(got.refill_ratio == want.refill_ratio);
  CHECK(got.nested_dissection_above == want.nested_dissection_above);
  CHECK(got.reorder_spread == want.reorder_spread);
  CHECK(got.reorder_spread_above == want.reorder_spread_above);
  CHECK(got.reorder_spread_nonzeros == want.reorder_spread_nonzeros);
  CHECK(got.reorder_spread_factors == want.reorder_spread_factors);
  CHECK(got.reorder_slice_ms == want.reorder_slice_ms);
  CHECK(got.rebuild_iterations == want.rebuild_iterations);
  CHECK(got.relinearize_work == want.relinearize_work);
  CHECK(got.heavy_relinearize_every == want.heavy_relinearize_every);
  // Not configurable here: it stays the smoother's own.
  CHECK(got.capacity_growth == want.capacity_growth);
}
}  // namespace

TEST_CASE("engine.graph.smoother: defaults are IncrementalOptions' own, every key reaches the graph stage's smoother") {
  const sextant::graph::IncrementalOptions defaults;
  // No key: the struct's defaults, and the shipped default.yaml documents the same values.
  const auto none = parse_daemon_config("", "t").engine.graph;
  check_smoother_options(planar_smoother_options(none), defaults);
  const auto shipped = sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  check_smoother_options(shipped.engine.graph.smoother, defaults);
  check_smoother_options(planar_smoother_options(shipped.engine.graph), defaults);

  // Every key set to a value that differs from its default: each one arrives in the smoother's options.
  const auto set =
      parse_daemon_config(
          "engine:\n  graph:\n    smoother:\n"
          "      relinearize_translation: 0.25\n      relinearize_rotation: 0.05\n      relinearization_passes: 3\n"
          "      relinearize_skip: 4\n      wildfire: 0\n      update_fraction: 0.1\n      min_update_factors: 16\n"
          "      max_update_factors: 512\n      refill_ratio: 2.5\n      nested_dissection_above: 100\n"
          "      reorder_spread: 3\n      reorder_spread_above: 0\n      reorder_slice_ms: 1.5\n"
          "      rebuild_iterations: 4\n      relinearize_work: 1000\n      reorder_spread_nonzeros: 7\n"
          "      reorder_spread_factors: 9\n      heavy_relinearize_every: 7\n",
          "t")
          .engine.graph;
  sextant::graph::IncrementalOptions want = defaults;
  want.relinearize_translation = 0.25, want.relinearize_rotation = 0.05, want.relinearization_passes = 3;
  want.relinearize_skip = 4, want.wildfire = 0, want.update_fraction = 0.1, want.min_update_factors = 16;
  want.max_update_factors = 512, want.refill_ratio = 2.5, want.nested_dissection_above = 100;
  want.reorder_spread = 3, want.reorder_spread_above = 0, want.reorder_slice_ms = 1.5, want.rebuild_iterations = 4;
  want.relinearize_work = 1000, want.reorder_spread_nonzeros = 7, want.reorder_spread_factors = 9;
  want.heavy_relinearize_every = 7;
  const sextant::graph::IncrementalOptions got = planar_smoother_options(set);
  check_smoother_options(got, want);
  // The kernel stays the loops' (DCS, auto width), whatever the smoother section says.
  CHECK(got.kernel == sextant::graph::RobustKernel::kDcs);
  CHECK(got.kernel_width == sextant::engine::kernel_width_for(set, true));
  // Defaults differ from the values set above (else the round trip would prove nothing).
  CHECK(defaults.relinearize_translation != want.relinearize_translation);
  CHECK(defaults.relinearize_skip != want.relinearize_skip);
  CHECK(defaults.wildfire != want.wildfire);
  CHECK(defaults.max_update_factors != want.max_update_factors);
  CHECK(defaults.refill_ratio != want.refill_ratio);
  CHECK(defaults.reorder_spread != want.reorder_spread);
  CHECK(defaults.reorder_spread_above != want.reorder_spread_above);
  CHECK(defaults.reorder_slice_ms != want.reorder_slice_ms);
  CHECK(defaults.rebuild_iterations != want.rebuild_iterations);
  CHECK(defaults.relinearize_work != want.relinearize_work);
  CHECK(defaults.reorder_spread_nonzeros != want.reorder_spread_nonzeros);
  CHECK(defaults.reorder_spread_factors != want.reorder_spread_factors);
  CHECK(defaults.heavy_relinearize_every != want.heavy_relinearize_every);
}

TEST_CASE("engine.graph.smoother: each bad value stops parsing with its line, column and key") {
  struct Bad {
    const char* key;
    const char* value;
    const char* why;
  };
  const std::vector<Bad> bad = {
      {"relinearize_translation", "0", "must be a positive number"},
      {"relinearize_rotation", "-0.1", "must be a positive number"},
      {"relinearize_rotation", "fast", "expected a number"},
      {"relinearization_passes", "-1", "must be in [0, 100]"},
      {"relinearize_skip", "0", "must be in [1, "},
      {"relinearize_skip", "1.5", "expected an integer"},
      {"wildfire", "-0.001", "must be >= 0"},
      {"update_fraction", "1.5", "must be in [0, 1]"},
      {"min_update_factors", "0", "must be in [1, "},
      {"max_update_factors", "0", "must be in [1, "},
      {"refill_ratio", "1", "must be a number > 1"},
      {"refill_ratio", ".inf", "must be a number > 1"},
      {"nested_dissection_above", "-5", "must be in [0, "},
      {"reorder_spread", "-1", "must be in [0, 1000]"},
      {"reorder_spread_above", "many", "expected an integer"},
      {"reorder_slice_ms", "-4", "must be >= 0"},
  };
  for (const Bad& b : bad) {
    const std::string key = b.key, value = b.value;
    CAPTURE(key);
    CAPTURE(value);
    const std::string e = error_of(std::string("engine:\n  graph:\n    smoother:\n      # latency\n      ") + b.key +
                                   ": " + b.value + "\n");
    const std::string place = "test.yaml:5:" + std::to_string(9 + std::string(b.key).size()) + ": ";
    CAPTURE(e);
    CHECK(e.find(place) == 0);
    CHECK(e.find("'engine.graph.smoother." + key + "'") != std::string::npos);
    CHECK(e.find(b.why) != std::string::npos);
  }
  // A cap below the floor names the key that was set.
  std::string e = error_of("engine:\n  graph:\n    smoother:\n      max_update_factors: 8\n");
  CHECK(e.find("test.yaml:4:27: 'engine.graph.smoother': max_update_factors (8) must not be smaller than "
               "min_update_factors (32)") == 0);
  e = error_of("engine:\n  graph:\n    smoother:\n      min_update_factors: 200\n");
  CHECK(e.find("test.yaml:4:27: 'engine.graph.smoother': max_update_factors (128) must not be smaller than "
               "min_update_factors (200)") == 0);
  // A misspelt key, the smoother section not a mapping, and the thresholds' old place.
  e = error_of("engine:\n  graph:\n    smoother:\n      reorder_spred: 2\n");
  CHECK(e.find("test.yaml:4:7: unknown key 'engine.graph.smoother.reorder_spred'") == 0);
  CHECK(e.find("reorder_spread") != std::string::npos);
  CHECK(error_of("engine:\n  graph:\n    smoother: 5\n")
            .find("test.yaml:3:15: 'engine.graph.smoother': expected a mapping") == 0);
  e = error_of("engine:\n  graph:\n    relinearize_translation: 0.2\n");
  CHECK(e.find("test.yaml:3:5: 'engine.graph.relinearize_translation' has moved to "
               "'engine.graph.smoother.relinearize_translation'") == 0);
}

TEST_CASE("landmark sightings' kernel width: auto takes the sighting gate's quantile of the sighting's dimension") {
  using sextant::assoc::chi2_quantile;
  using sextant::engine::sighting_kernel_width_for;
  // Planar sightings have 2 residuals (range, bearing), 3-D ones 3; the gate is landmarks.gate_probability (0.999):
  // the tables' 13.816 and 16.266.
  const auto d = parse_daemon_config("", "t").engine.graph;
  CHECK(sighting_kernel_width_for(d, true) == chi2_quantile(2, 0.999));
  CHECK(sighting_kernel_width_for(d, false) == chi2_quantile(3, 0.999));
  CHECK(sighting_kernel_width_for(d, true) == doctest::Approx(13.816).epsilon(1e-4));
  CHECK(sighting_kernel_width_for(d, false) == doctest::Approx(16.266).epsilon(1e-4));
  // The sightings' own gate probability, not the loops'; Huber and Cauchy take the square root.
  const auto huber = parse_daemon_config(
                         "engine:\n  graph:\n    loops: {robust: huber, gate_probability: 0.9}\n    landmarks: "
                         "{gate_probability: 0.99}\n",
                         "t")
                         .engine.graph;
  CHECK(sighting_kernel_width_for(huber, true) == doctest::Approx(std::sqrt(chi2_quantile(2, 0.99))));
  CHECK(sighting_kernel_width_for(huber, true) == doctest::Approx(std::sqrt(9.2103)).epsilon(1e-4));
  // A configured number applies to sightings too.
  const auto five = parse_daemon_config("engine:\n  graph:\n    loops: {kernel_width: 5}\n", "t").engine.graph;
  CHECK(sighting_kernel_width_for(five, true) == 5.0);
  CHECK(sighting_kernel_width_for(five, false) == 5.0);
}

TEST_CASE("a key that is not a plain name is a ConfigError with file:line, not a YAML exception") {
  std::string e;
  CHECK_NOTHROW(e = error_of("daemon:\n  [a]: 1\n"));
  CHECK(e.find("test.yaml:2:3:") == 0);
  CHECK(e.find("a key must be a plain name") != std::string::npos);
  CHECK(error_of("{a: 1}: 2\n").find("test.yaml") == 0);
}

TEST_CASE("a key of a user-named map that is not a plain name is refused with its line (sources, mountings, markers)") {
  // A null key once read as the name "null", and looking that name up inserted it into the map being iterated.
  const std::string sources = "engine:\n  filter:\n    sources:\n      :\n      wheel: {body: r}\n";
  const std::string mountings = "engine:\n  inertial:\n    mountings:\n      wheel: {}\n      ~: {}\n";
  const std::string markers = "engine:\n  graph:\n    fleet:\n      markers: {1: robot1, [2]: robot2}\n";
  for (const auto& [yaml, place] : {std::pair{sources, "test.yaml:4:7:"}, std::pair{mountings, "test.yaml:5:7:"},
                                    std::pair{markers, "test.yaml:4:28:"}}) {
    std::string e;
    CHECK_NOTHROW(e = error_of(yaml));
    CHECK_MESSAGE(e.find(place) == 0, e);
    CHECK_MESSAGE(e.find("a key must be a plain name") != std::string::npos, e);
  }
}

TEST_CASE("reading a section never adds a key to the YAML it reads") {
  YAML::Node root = YAML::Load("a: 1\nb: {c: 2}\n");
  sextant::config::Section s(root, "", "t.yaml");
  int a = 0, missing = 7;
  s.get("a", a);
  s.get("absent", missing);
  sextant::config::Section absent = s.child("no_such_section");
  absent.get("x", missing);
  CHECK(s.place_of("also_absent").IsMap());
  CHECK(a == 1);
  CHECK(missing == 7);
  CHECK_FALSE(absent.node().IsDefined());
  CHECK(root.size() == 2);
  CHECK(s.keys().size() == 2);
}

TEST_CASE("load_daemon_config names the file in every error") {
  const std::string dir = std::string(SEXTANT_SOURCE_DIR) + "/config";
  try {
    sextant::config::load_daemon_config(dir);
    FAIL("a directory parsed");
  } catch (const ConfigError& e) {
    CHECK(std::string(e.what()).find(dir) == 0);
  }
}

TEST_CASE(
    "channels that cannot work are refused: LCM's 63-character limit with the prefix, shared inputs, outputs "
    "named like inputs") {
  const std::string prefix(70, 'P');
  std::string e = error_of("channels:\n  prefix: " + prefix + "\n");
  CHECK(e.find("test.yaml:2:") == 0);
  CHECK(e.find("LCM allows 63") != std::string::npos);
  // 50 + "FUSED_POSE_DEAD_RECKONING" (25) is over; the inputs alone would fit.
  e = error_of("channels:\n  prefix: " + std::string(40, 'P') + "\n");
  CHECK(e.find("channels.fused_pose': channel '" + std::string(40, 'P') + "FUSED_POSE_DEAD_RECKONING' is 65") !=
        std::string::npos);
  CHECK(error_of("channels:\n  prefix: " + std::string(30, 'P') + "\n").empty());
  e = error_of("channels:\n  odometry: SENSORS\n  landmarks: SENSORS\n");
  CHECK(e.find("test.yaml:3:") == 0);
  CHECK(e.find("channels.landmarks': the same channel as channels.odometry") != std::string::npos);
  e = error_of("channels:\n  fused_pose: ODOMETRY\n");
  CHECK(e.find("test.yaml:2:") == 0);
  CHECK(e.find("is also the input channels.odometry") != std::string::npos);
  CHECK(error_of("channels:\n  status: TRAJECTORY\n").find("the same channel as channels.trajectory") !=
        std::string::npos);
}

TEST_CASE("a config without primary_estimator puts the same estimator on FUSED_POSE as config/default.yaml") {
  const auto d = sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  const auto empty = parse_daemon_config("", "empty.yaml");
  CHECK(d.engine.primary_estimator == sextant::engine::PrimaryEstimator::kEkf);
  CHECK(empty.engine.primary_estimator == d.engine.primary_estimator);
  CHECK(sextant::engine::Engine(empty.engine).primary_estimator() == "ekf");
  // Without the EKF, the named estimator falls back to "auto" (here dead reckoning) instead of publishing nothing.
  const auto dr = parse_daemon_config("engine:\n  filter:\n    type: none\n  graph:\n    enabled: false\n", "dr.yaml");
  CHECK(sextant::engine::Engine(dr.engine).primary_estimator() == "dead_reckoning");
}

TEST_CASE("the guard and bound keys of the daemon section: defaults as documented, bad values refused") {
  const auto d = sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  const auto empty = parse_daemon_config("", "empty.yaml");
  CHECK(d.max_ahead_s == empty.max_ahead_s);
  CHECK(d.time_resync_messages == empty.time_resync_messages);
  CHECK(d.max_ahead_of_wall_s == empty.max_ahead_of_wall_s);
  CHECK(d.max_sources == empty.max_sources);
  CHECK(d.source_idle_s == empty.source_idle_s);
  CHECK(d.drain_timeout_s == empty.drain_timeout_s);
  const auto c =
      parse_daemon_config("daemon:\n  max_sources: 7\n  drain_timeout_s: 0.5\n  time_resync_messages: 3\n", "t.yaml");
  CHECK(c.max_sources == 7);
  CHECK(c.drain_timeout_s == 0.5);
  CHECK(c.time_resync_messages == 3);
  CHECK(error_of("daemon:\n  max_sources: 0\n").find("test.yaml:2:") == 0);
  CHECK(error_of("daemon:\n  max_ahead_s: -1\n").find("test.yaml:2:") == 0);
}

TEST_CASE("engine.graph.lifelong: a budget per kind of body, the old shared keys refused with their replacement") {
  const auto d = parse_daemon_config("", "t").engine.graph.lifelong;
  CHECK(d.enabled);
  CHECK(d.budget(true).max_keyframes == 2000);
  CHECK(d.budget(true).window == 1000);
  CHECK(d.budget(false).max_keyframes == 1000);
  CHECK(d.budget(false).window == 500);
  const auto set = parse_daemon_config(
                       "engine:\n  graph:\n    lifelong:\n      planar: {max_keyframes: 300, window: 100}\n      "
                       "spatial: {max_keyframes: 40}\n",
                       "t")
                       .engine.graph.lifelong;
  CHECK(set.planar.max_keyframes == 300);
  CHECK(set.planar.window == 100);
  CHECK(set.spatial.max_keyframes == 40);
  CHECK(set.spatial.window == 500);
  const std::string gone = error_of("engine:\n  graph:\n    lifelong:\n      max_keyframes: 300\n");
  CHECK(gone.find("test.yaml:4:") == 0);
  CHECK(gone.find("'engine.graph.lifelong.planar.max_keyframes'") != std::string::npos);
  const std::string bad = error_of("engine:\n  graph:\n    lifelong:\n      spatial: {window: 0}\n");
  CHECK(bad.find("test.yaml:4:") == 0);
  CHECK(bad.find("engine.graph.lifelong.spatial.window") != std::string::npos);
}

TEST_CASE("config: daemon.plausibility and source_handover_s are read and checked with file:line") {
  const auto c = sextant::config::parse_daemon_config(
      "daemon:\n  source_handover_s: 5\n  plausibility:\n    max_speed_planar_mps: 3\n    max_range_m: 80\n", "t.yaml");
  CHECK(c.source_handover_s == 5);
  CHECK(c.plausibility.max_speed_planar_mps == 3);
  CHECK(c.plausibility.max_range_m == 80);
  CHECK(c.plausibility.max_speed_spatial_mps == 350);
  CHECK(sextant::test::config_error_of("daemon:\n  plausibility:\n    max_range_m: -1\n").find("test.yaml:3:") == 0);
  CHECK(sextant::test::config_error_of("daemon:\n  plausibility:\n    max_rnge_m: 1\n").find("test.yaml:3:") == 0);
}

TEST_CASE(
    "config: strict reading: duplicate keys, several documents, control characters, bad prefixes, non-regular files") {
  using sextant::test::config_error_of;
  CHECK(config_error_of("daemon:\n  name: a\n  name: b\n").find("test.yaml:3:3: key 'name' written twice") == 0);
  CHECK(config_error_of("daemon:\n  name: a\ndaemon:\n  name: b\n").find("test.yaml:3:1: key 'daemon' written twice") ==
        0);
  CHECK(config_error_of("daemon:\n  name: a\n---\ndaemon:\n  name: b\n").find("test.yaml:3: a second YAML document") ==
        0);
  CHECK(config_error_of(std::string("daemon:\n  name: \"a\\0b\"\n") + std::string(1, '\0'))
            .find("test.yaml:3:1: control character 0x0") == 0);
  CHECK(config_error_of("daemon:\n  name: a\x1b[2Jb\n").find("test.yaml:2:10: control character 0x1b") == 0);
  CHECK(config_error_of("channels:\n  prefix: \"ROBOT 1_\"\n").find("test.yaml:2:11:") == 0);
  CHECK(config_error_of("channels:\n  prefix: \"R\xc3\xa9_\"\n").find("test.yaml:2:11:") == 0);
  CHECK(config_error_of("channels:\n  prefix: \"ROBOT1_\"\n").empty());
  CHECK(config_error_of(std::string(sextant::config::kMaxConfigBytes + 1, '#')).find("bytes; a config is at most") !=
        std::string::npos);
  const auto load_error = [](const std::string& path) {
    try {
      sextant::config::load_daemon_config(path);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(load_error("/dev/zero") == "/dev/zero: not a regular file");
  const std::string fifo = "/tmp/sextant_config_fifo_" + std::to_string(::getpid());
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK(load_error(fifo) == fifo + ": not a regular file");  // would block for ever if it were opened
  ::unlink(fifo.c_str());
}

TEST_CASE("config: a control character written as a YAML escape in daemon.name is refused too") {
  CHECK(sextant::test::config_error_of("daemon:\n  name: \"a\\0b\"\n")
            .find("test.yaml:2:9: 'daemon.name': must not contain control characters") == 0);
}

TEST_CASE(
    "config: document markers: a leading '---' and a final '...' are one document, content after them is a second") {
  using sextant::test::config_error_of;
  CHECK(config_error_of("---\ndaemon:\n  name: a\n...\n").empty());
  CHECK(config_error_of("daemon:\n  name: a\n...\ndaemon:\n  name: b\n").find("test.yaml:4: a second YAML document") ==
        0);
  CHECK(config_error_of(",").find("test.yaml:") ==
        0);  // malformed: an error, and it returns (yaml-cpp's LoadAll did not)
}
