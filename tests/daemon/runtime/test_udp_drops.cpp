// The kernel's receive-buffer drops of this process's UDP sockets, as /proc reports them: a socket with a tiny
// buffer that nobody reads loses what a burst sends it, and udp_receive_drops() counts exactly those datagrams.
#include "daemon/runtime/udp_drops.hpp"

#include <doctest/doctest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <vector>

TEST_CASE("udp_receive_drops counts datagrams the kernel dropped for a full receive buffer") {
  const auto before = sextant::runtime::udp_receive_drops();
  if (!before) {
    MESSAGE("no /proc/net/udp here: nothing to check");
    return;
  }
  const int rx = ::socket(AF_INET, SOCK_DGRAM, 0), tx = ::socket(AF_INET, SOCK_DGRAM, 0);
  REQUIRE(rx >= 0);
  REQUIRE(tx >= 0);
  const int small = 4096;
  ::setsockopt(rx, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::bind(rx, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  socklen_t len = sizeof addr;
  REQUIRE(::getsockname(rx, reinterpret_cast<sockaddr*>(&addr), &len) == 0);
  const std::vector<char> payload(1000, 'x');
  const int sent = 500;
  for (int i = 0; i < sent; ++i)
    ::sendto(tx, payload.data(), payload.size(), 0, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  // What the buffer kept is readable; everything else was dropped.
  int queued = 0;
  char buf[2000];
  while (::recv(rx, buf, sizeof buf, MSG_DONTWAIT) > 0) ++queued;
  const auto after = sextant::runtime::udp_receive_drops();
  REQUIRE(after.has_value());
  CHECK(queued < sent);
  CHECK(*after - *before == sent - queued);
  ::close(rx);
  ::close(tx);
}
