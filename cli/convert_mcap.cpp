// sextant convert mcap IN.lcm -o OUT.mcap | lcm IN.mcap -o OUT.lcm: LCM logs to MCAP files that Foxglove opens (the
// bridge's topics and schemas: viewer/topics.hpp) and back.  Registered under the name "convert mcap" so that it
// sorts after "convert" (main.cpp adds commands by name) and adds its formats to that subcommand.
#include "cli/command.hpp"
#include "cli/convert_command.hpp"
#include "viewer/lcm_mcap.hpp"

#include <chrono>
#include <cstdio>

namespace {

using namespace sextant::viewer;

sextant::cli::RegisterCommand reg{
    "convert mcap", [](CLI::App& app) {
      auto* convert = sextant::cli::convert_command(app);

      auto* mcap = convert->add_subcommand("mcap",
                                           "an LCM log -> an MCAP file for Foxglove (every sextant channel as JSON "
                                           "with its schema, plus poses, frames and 3-D scene topics)");
      auto m_in = std::make_shared<std::string>(), m_out = std::make_shared<std::string>();
      auto m_opt = std::make_shared<McapWriterOptions>();
      mcap->add_option("log", *m_in, "LCM log")->required()->check(CLI::ExistingFile);
      mcap->add_option("-o,--output", *m_out, "output MCAP file")->required();
      mcap->add_option("--chunk-size", m_opt->chunk_size, "uncompressed bytes per chunk")
          ->check(CLI::Range(size_t{4096}, size_t{1} << 30));
      mcap->add_option("--zstd-level", m_opt->zstd_level, "zstd compression level")->check(CLI::Range(1, 19));
      mcap->callback([=] {
        sextant::cli::convert_guarded("mcap", [&] {
          const auto t0 = std::chrono::steady_clock::now();
          const auto r = convert_lcm_to_mcap(*m_in, *m_out, *m_opt);
          const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          std::printf(
              "%s: %lld LCM events (%lld kept as raw LCM) -> %llu MCAP messages on %u channels in %u chunks; "
              "%.1f MB -> %.1f MB (%.2fx) in %.2f s (%.1f MB/s of LCM log)\n",
              m_out->c_str(), (long long)r.events, (long long)r.raw, (unsigned long long)r.statistics.message_count,
              r.statistics.channel_count, r.statistics.chunk_count, r.bytes_in / 1e6, r.bytes_out / 1e6,
              r.bytes_out > 0 ? double(r.bytes_in) / double(r.bytes_out) : 0.0, s, s > 0 ? r.bytes_in / 1e6 / s : 0.0);
          if (!r.log_damage.empty())
            std::fprintf(stderr, "sextant convert mcap: %s: %s\n", m_in->c_str(), r.log_damage.c_str());
        });
      });

      auto* lcm =
          convert->add_subcommand("lcm", "an MCAP file written by sextant -> the LCM log of its sextant channels");
      auto l_in = std::make_shared<std::string>(), l_out = std::make_shared<std::string>();
      lcm->add_option("mcap", *l_in, "MCAP file")->required()->check(CLI::ExistingFile);
      lcm->add_option("-o,--output", *l_out, "output LCM log")->required();
      lcm->callback([=] {
        sextant::cli::convert_guarded("lcm", [&] {
          const auto r = convert_mcap_to_lcm(*l_in, *l_out);
          std::printf("%s: %lld LCM events (%lld view messages skipped)\n", l_out->c_str(), (long long)r.events,
                      (long long)r.views_skipped);
        });
      });
    }};

}  // namespace
