"""Summary of a fleet-of-daemons run (bench/fleet_hosts_mrclam.sh): from each host's status messages (busN.lcm), how long
after the heal (WORK/healed) the host had applied every contribution the other hosts had made by the heal (its
fleet_in_delivered reaching the sum of the others' fleet_out_contributions in their last reports before the heal;
nothing lost, nothing restarted), the contributions it held ahead of a gap (fleet_in_held: median before the cut
(WORK/cut), peak after the heal), its streams' losses, and the fleet traffic it published (FLEET + FLEET_CONTROL
bytes) per robot per second of data in each third of the run.  Usage: fleet_hosts_summary.py WORK DATA_SECONDS HOSTS"""
import sys

from lcmlog import read_log
from sextant import status_t


def status_reports(path):
    """(wall s, counters by name, FLEET + FLEET_CONTROL bytes published) of every status message in a host's log."""
    out = []
    for _, channel, data in read_log(path):
        if not channel.endswith("SEXTANT_STATUS"):
            continue
        m = status_t.decode(data)
        counters = {}
        for s in m.stages:
            counters.update(zip(s.counter_names, s.counter_values))
        fleet = sum(b for c, b in zip(m.output_channels, m.output_bytes) if c in ("FLEET", "FLEET_CONTROL"))
        out.append((m.utime / 1e6, counters, fleet))
    return out


def main():
    work, data_s, hosts = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    healed = float(open(f"{work}/healed").read())
    start = float(open(f"{work}/start").read())
    played = float(open(f"{work}/played").read())
    print("| host | held before the cut (median) / peak after | all made before the heal applied, after (s) | lost | "
          "FLEET bytes per robot per data-second, thirds of the run |")
    print("|---|---|---|---|---|")
    reports = {h: status_reports(f"{work}/bus{h}.lcm") for h in range(1, hosts + 1)}
    made = {h: max((c.get("fleet_out_contributions", 0) for t, c, _ in reports[h] if t <= healed), default=0)
            for h in reports}
    for h in range(1, hosts + 1):
        others = sum(made[o] for o in made if o != h)
        caught_up = next((t - healed for t, c, _ in reports[h] if t >= healed and c.get("fleet_in_delivered", 0) >= others),
                         float("nan"))
        samples = [(t, c.get("fleet_in_held", 0), c.get("fleet_in_lost", 0), fleet) for t, c, fleet in reports[h]]
        cut = float(open(f"{work}/cut").read())
        before = sorted(held for t, held, _, _ in samples if start <= t <= cut) or [0]
        usual = before[len(before) // 2]
        peak = max((held for t, held, _, _ in samples if t >= healed), default=0)
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
        print(f"| host{h} | {usual} / {peak} | {caught_up:.1f} | {samples[-1][2] if samples else '?'} | {' / '.join(thirds)} |")


if __name__ == "__main__":
    main()
