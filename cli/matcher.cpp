// sextant matcher --truth LOG.lcm [--lcm-url URL] [--sigma-t M] [--sigma-r RAD] [--failure-rate P] [--wrong-rate P]
//                 [--seed N] [--delay-ms D] [--seconds S] [--json]
// A simulated loop-closure front end: answers MATCH_REQUESTS on LOOP_CLOSURES from the log's ground truth with
// noise, failures and wrong matches (sim/simulated_matcher.hpp has the model), until SIGINT/SIGTERM.
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/wire_layout.hpp"
#include "daemon/runtime/raw_subscription.hpp"
#include "cli/command.hpp"
#include "cli/handle_until_stopped.hpp"
#include "report/json_writer.hpp"
#include "sim/simulated_matcher.hpp"
#include "cli/log_damage_report.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <deque>

namespace {

using Clock = std::chrono::steady_clock;

struct MatcherNode {
  MatcherNode(lcm::LCM& l, sextant::tools::SimulatedMatcher& m, std::string channel, std::chrono::microseconds d)
      : lcm(l), matcher(m), answer_channel(std::move(channel)), delay(d) {}
  lcm::LCM& lcm;
  sextant::tools::SimulatedMatcher& matcher;
  std::string answer_channel;
  std::chrono::microseconds delay{0};
  int64_t seq = 0, undecodable = 0, published = 0;
  std::deque<std::pair<Clock::time_point, sextant::loop_closure_t>> pending;  // answers in due order

  void on_message(const lcm_recv_buf_t& b, const std::string&) {
    sextant::match_request_t m;
    if (sextant::runtime::safe_decode(b.data, b.data_size, m)) {
      ++undecodable;
      return;
    }
    if (auto lc = matcher.answer(sextant::runtime::to_output(m)))
      pending.emplace_back(Clock::now() + delay, sextant::runtime::to_message(*lc, matcher.options().name, seq++));
    publish_due();
  }

  void publish_due() {
    const auto now = Clock::now();
    while (!pending.empty() && pending.front().first <= now) {
      lcm.publish(answer_channel, &pending.front().second);
      pending.pop_front();
      ++published;
    }
  }

  /// Milliseconds until the next answer is due (at most `cap`).
  int wait_ms(int cap) const {
    if (pending.empty()) return cap;
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(pending.front().first - Clock::now()).count();
    return static_cast<int>(std::clamp<int64_t>(ms, 0, cap));
  }
};

// The matcher's counts on exit: JSON with --json, else one line.
template <class Counts>
void print_counts(const Counts& c, const MatcherNode& node, bool json) {
  if (json) {
    sextant::tools::JsonWriter j;
    j.begin_object();
    j.field("requests", c.requests).field("answered", c.answered).field("wrong", c.wrong);
    j.field("failed", c.failed).field("out_of_span", c.out_of_span).field("invalid", c.invalid);
    j.field("undecodable", node.undecodable).field("published", node.published);
    j.field("unsent", node.pending.size());
    j.end_object();
    std::fputs(j.str().c_str(), stdout);
  } else {
    std::printf(
        "sextant matcher: %lld requests: %lld answered, %lld wrong, %lld failed, %lld out of span, "
        "%lld invalid, %lld undecodable; %lld published, %zu unsent\n",
        (long long)c.requests, (long long)c.answered, (long long)c.wrong, (long long)c.failed, (long long)c.out_of_span,
        (long long)c.invalid, (long long)node.undecodable, (long long)node.published, node.pending.size());
  }
}

sextant::cli::RegisterCommand reg{
    "matcher", [](CLI::App& app) {
      auto* cmd = app.add_subcommand("matcher",
                                     "simulated loop-closure front end: answer MATCH_REQUESTS from a log's "
                                     "ground truth with noise, failures and wrong matches");
      auto o = std::make_shared<sextant::tools::SimulatedMatcherOptions>();
      auto truth = std::make_shared<std::string>();
      auto url = std::make_shared<std::string>();
      auto requests = std::make_shared<std::string>("MATCH_REQUESTS");
      auto answers = std::make_shared<std::string>("LOOP_CLOSURES");
      auto delay_ms = std::make_shared<double>(0);
      auto seconds = std::make_shared<double>(0);
      auto json = std::make_shared<bool>(false);
      cmd->add_option("--truth", *truth,
                      "LCM log with the ground truth (GROUND_TRUTH, as written by simulate and "
                      "convert tum)")
          ->required();
      cmd->add_option("--lcm-url", *url, "LCM URL");
      cmd->add_option("--sigma-t", o->sigma_t, "translation noise standard deviation, m (per axis)")
          ->check(CLI::PositiveNumber);
      cmd->add_option("--sigma-r", o->sigma_r, "rotation noise standard deviation, rad (per axis)")
          ->check(CLI::PositiveNumber);
      cmd->add_option("--failure-rate", o->failure_rate, "fraction of requests left unanswered")
          ->check(CLI::Range(0.0, 1.0));
      cmd->add_option("--wrong-rate", o->wrong_rate, "fraction of requests answered with a wrong match")
          ->check(CLI::Range(0.0, 1.0));
      cmd->add_option("--seed", o->seed, "random seed (the same seed and requests give the same answers)");
      cmd->add_option("--delay-ms", *delay_ms, "answer this long after the request arrives")
          ->check(CLI::NonNegativeNumber);
      cmd->add_option("--requests", *requests, "request channel");
      cmd->add_option("--answers", *answers, "answer channel");
      cmd->add_option("--seconds", *seconds, "exit after this many seconds (default: run until SIGINT/SIGTERM)");
      cmd->add_flag("--json", *json, "print the counts as JSON on exit");
      auto tolerate_damage = std::make_shared<bool>(false);
      cmd->add_flag("--tolerate-damage", *tolerate_damage, sextant::cli::kTolerateDamageHelp);
      cmd->callback([=] {
        sextant::runtime::LogDamage damage;
        sextant::tools::SimulatedMatcher matcher(sextant::tools::read_matcher_truth(*truth, &damage), *o);
        // Before the bus: a damaged truth log is said at once (with exit 4 unless tolerated), not after the run.
        sextant::cli::report_log_damage("sextant matcher", *truth, damage, *tolerate_damage);
        lcm::LCM lcm(*url);
        if (!lcm.good()) {
          std::fprintf(stderr,
                       "sextant matcher: cannot start LCM on '%s' (is there a multicast route? "
                       "sudo ip route add 224.0.0.0/4 dev lo)\n",
                       url->c_str());
          throw CLI::RuntimeError(3);
        }
        MatcherNode node(lcm, matcher, *answers, std::chrono::microseconds(static_cast<int64_t>(*delay_ms * 1000)));
        sextant::runtime::subscribe_raw(lcm, *requests, &node);

        auto& stop = sextant::cli::stop_requested();
        std::signal(SIGINT, [](int) { sextant::cli::stop_requested() = true; });
        std::signal(SIGTERM, [](int) { sextant::cli::stop_requested() = true; });
        const auto start = Clock::now();
        while (!stop) {
          lcm.handleTimeout(std::max(1, node.wait_ms(100)));
          node.publish_due();
          if (*seconds > 0 && std::chrono::duration<double>(Clock::now() - start).count() > *seconds) break;
        }

        print_counts(matcher.counts(), node, *json);
        std::fflush(stdout);
      });
    }};

}  // namespace
