#pragma once
// Datagrams the kernel dropped before this process could read them (its UDP sockets' receive buffers overflowed),
// where Linux reports them: the `drops` column of /proc/net/udp and /proc/net/udp6 for the sockets this process
// holds (matched by inode through /proc/self/fd).  LCM's UDP multicast loses messages this way under bursts;
// `lost` on SEXTANT_STATUS (sequence gaps) counts them per channel, this counts them per process, including
// messages of channels the daemon does not read.  A larger buffer: `?recv_buf_size=BYTES` in the LCM URL.
#include <cstdint>
#include <optional>

namespace sextant::runtime {

/// The sum of the kernel's drop counters over this process's UDP sockets; nullopt where /proc does not say.
std::optional<int64_t> udp_receive_drops();

}  // namespace sextant::runtime
