"""Summary of a fleet-of-daemons run (bench/fleet_hosts_mrclam.sh): from each host's status messages (busN.lcm), the
time after the heal (WORK/healed) at which the host held, after its peak, no more back than it usually did before the cut (WORK/cut;
fleet_in_held), its streams' losses,
and the fleet traffic it published (FLEET + FLEET_CONTROL bytes) per robot per second of data in each third of the
run.  Usage: fleet_hosts_summary.py WORK DATA_SECONDS HOSTS"""
import sys

from lcmlog import read_log
from sextant import status_t


def main():
    work, data_s, hosts = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    healed = float(open(f"{work}/healed").read())
    start = float(open(f"{work}/start").read())
    played = float(open(f"{work}/played").read())
    print("| host | held before the cut (median) / peak after | whole again after the heal (s) | lost | "
          "FLEET bytes per robot per data-second, thirds of the run |")
    print("|---|---|---|---|---|")
    for h in range(1, hosts + 1):
        samples = []  # (wall s, held, lost, fleet bytes)
        for _, channel, data in read_log(f"{work}/bus{h}.lcm"):
            if not channel.endswith("SEXTANT_STATUS"):
                continue
            m = status_t.decode(data)
            counters = {}
            for s in m.stages:
                counters.update(zip(s.counter_names, s.counter_values))
            fleet = sum(b for c, b in zip(m.output_channels, m.output_bytes) if c in ("FLEET", "FLEET_CONTROL"))
            samples.append((m.utime / 1e6, counters.get("fleet_in_held", 0), counters.get("fleet_in_lost", 0), fleet))
        # Under steady loss some contributions are always held for a repair: "whole again" is the first report after
        # the heal holding no more than the median report before the cut did.
        cut = float(open(f"{work}/cut").read())
        before = sorted(held for t, held, _, _ in samples if start <= t <= cut) or [0]
        usual = before[len(before) // 2]
        after = [(t, held) for t, held, _, _ in samples if t >= healed]
        peak_at, peak = max(after, key=lambda x: x[1], default=(healed, 0))
        whole = next((t - healed for t, held in after if t >= peak_at and held <= usual), float("nan"))
        thirds = []
        span = (played - start) / 3
        for k in range(3):
            a, b = start + k * span, start + (k + 1) * span
            inside = [x for x in samples if a <= x[0] <= b]
            if len(inside) < 2:
                thirds.append("?")
                continue
            bytes_ = inside[-1][3] - inside[0][3]
            data_seconds = (inside[-1][0] - inside[0][0]) * data_s / (played - start)
            thirds.append(f"{bytes_ / data_seconds:.0f}")
        print(f"| host{h} | {usual} / {peak} | {whole:.1f} | {samples[-1][2] if samples else '?'} | {' / '.join(thirds)} |")


if __name__ == "__main__":
    main()
