# Shared by the fleet's end-to-end scripts: several test hosts on one machine, each a network namespace with one
# interface on a common bridge (a LAN), made and removed by the script itself.  Sourced inside a lab: a process in a
# private network and mount namespace (`unshare --net --mount`), so that the bridge, the hosts and their names
# (/run/netns, a tmpfs private to the lab) vanish with it and nothing reaches the machine's own network.

# LCM across the bridge: multicast with ttl=1 (one LAN hop), large receive buffers.
export LCM_LAB_URL="udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304"

# lab_init: the bridge and a private /run/netns.
lab_init() {
  mkdir -p /run/netns
  mount -t tmpfs lab-netns /run/netns
  ip link add lab-br type bridge
  ip link set lab-br up
}

# lab_host N: host hN with interface eN (10.77.0.N/24) on the bridge, its lab-side end lab-vN, multicast routed to it.
lab_host() {
  local n=$1
  ip netns add "h$n"
  ip link add "lab-v$n" type veth peer name "e$n"
  ip link set "e$n" netns "h$n"
  ip link set "lab-v$n" master lab-br
  ip link set "lab-v$n" up
  ip netns exec "h$n" ip link set lo up
  ip netns exec "h$n" ip addr add "10.77.0.$n/24" dev "e$n"
  ip netns exec "h$n" ip link set "e$n" up
  ip netns exec "h$n" ip route add 224.0.0.0/4 dev "e$n"
}

# lab_loss N PERCENT: host hN drops PERCENT % of the LCM datagrams it receives from the other hosts (nftables; the
# kernel here has no netem).
lab_loss() {
  local n=$1 percent=$2
  ip netns exec "h$n" nft add table inet lab
  ip netns exec "h$n" nft add chain inet lab input '{ type filter hook input priority 0; }'
  ip netns exec "h$n" nft add rule inet lab input iifname "e$n" ip saddr != "10.77.0.$n" udp dport 7667 \
    numgen random mod 100 '<' "$percent" drop
}

# lab_cut N / lab_heal N: host hN's cable out of the bridge and back.
lab_cut() { ip link set "lab-v$1" down; }
lab_heal() { ip link set "lab-v$1" up; }

# in_host N CMD... &: CMD on host hN with the lab's LCM URL, in the background; it replaces the subshell the '&'
# made, so that $! is CMD itself (a signal to $! reaches it).
in_host() {
  local n=$1
  shift
  exec ip netns exec "h$n" env LCM_DEFAULT_URL="$LCM_LAB_URL" "$@"
}
