"""`make bench-sensors`: the local estimate at a scene's sensors against Mitsuba 3 irradiance
meters on the same scene in the same run, with luxest's backward estimate (`estimate gather`) as
a second luxest column. CPU seconds until a sensor's relative standard error reaches 1 %: for the
local estimate, one `estimate sensors` run serves every sensor, so a sensor reaches 1 % at
t · (r_i / 0.01)² (r_i its relative standard error after t CPU-s); the backward estimate spends
its samples per sensor, so every sensor costs the sum; for Mitsuba each sensor is
a render of its own (an `irradiancemeter` on a disk of radius --disk-radius at the evaluated
point, facing the sensor's normal), so every sensor at 1 % costs the sum over sensors. Runs in
.venv-peers (numpy, mitsuba); Mitsuba's CPU-s count its renders (`dr.eval`), not the JIT warm-up
render of each sensor. Sensors with no light (value 0) are left out.

Mitsuba's integrator is `path` (light reaches the meter by directions sampled from it, with no
next-event estimation there). Its `ptracer`, which would connect every light-path vertex to the
meter, is wrong for irradiance meters in Mitsuba 3.9.1: the meter's `sample_direction` weight
ignores the distance (mitsuba3 pull request #1848). On the Cornell box floor at (0.357, 0, 0.028)
and (0.137, 0, 0.363), 4 × 4096 samples: `ptracer` 0.574 ± 0.001 and 0.658 ± 0.001, `path`
0.438 ± 0.03 and 0.712 ± 0.03, luxest's local estimate 0.4489 ± 0.0002 and 0.7327 ± 0.0007 (its
backward estimate 0.4492 ± 0.0016 and 0.7325 ± 0.0023). The table checks the values: per sensor
z = (Mitsuba − luxest) / √(se² + se²)."""

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from luxest_contract import luminance, read_sensors_csv, sensors_name  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from atomic import write_text  # noqa: E402
from bench_pt import child_cpu  # noqa: E402
from host import host_summary  # noqa: E402
from mitsuba_render import scene_xml  # noqa: E402

TARGET = 0.01


def luxest(a, work):
    """Runs `estimate sensors`; returns (CPU-s, [(position, normal, value, standard_error)])."""
    out = sensors_name(work, "luxest")
    table = out.with_suffix(".csv")
    cpu, _ = child_cpu([a.estimate, "sensors", a.scene, "--paths", a.paths, "-o", out, "--csv", table])
    rows, _ = read_sensors_csv(table)
    sensors = []
    for r in rows:
        p = tuple(float(r[f"evaluated_{c}"]) for c in "xyz")
        n = tuple(float(r[f"n{c}"]) for c in "xyz")
        sensors.append((p, n, r["value"], r["standard_error"]))
    return cpu, sensors


def gather(a, work):
    """Runs `estimate gather` (luxest's backward estimate, a sample budget per sensor); returns
    (CPU-s, [(value, standard_error)])."""
    out = sensors_name(work, "gather")
    table = out.with_suffix(".csv")
    cpu, _ = child_cpu([a.estimate, "gather", a.scene, "--samples", a.gather_samples, "-o", out, "--csv", table])
    rows, _ = read_sensors_csv(table)
    return cpu, [(r["value"], r["standard_error"]) for r in rows]


def meter_xml(i, position, normal, radius, spp):
    p = position
    t = tuple(p[k] + normal[k] for k in range(3))
    up = (0.0, 0.0, 1.0) if abs(normal[2]) < 0.9 else (1.0, 0.0, 0.0)
    f = lambda v: ", ".join(f"{x:.9g}" for x in v)
    return (
        f'<shape type="disk" id="meter{i}"><transform name="to_world"><scale value="{radius:.9g}"/>'
        f'<lookat origin="{f(p)}" target="{f(t)}" up="{f(up)}"/></transform>'
        f'<sensor type="irradiancemeter" id="meter{i}_sensor"><film type="hdrfilm"><integer name="width" value="1"/>'
        f'<integer name="height" value="1"/><rfilter type="box"/><string name="pixel_format" value="rgb"/>'
        f'<string name="component_format" value="float32"/></film>'
        f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler></sensor></shape>'
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True, help="compiled scene (.lxs)")
    ap.add_argument("--mitsuba-scene", required=True, help="the same scene exported for Mitsuba (scene.xml)")
    ap.add_argument("--estimate", required=True)
    ap.add_argument("--paths", type=int, default=400000, help="light paths of the luxest run")
    ap.add_argument("--spp", type=int, default=65536, help="samples per estimate of a Mitsuba meter")
    ap.add_argument(
        "--gather-samples",
        type=int,
        default=20000,
        help="samples per sensor of luxest's backward estimate (estimate gather)",
    )
    ap.add_argument("--replicates", type=int, default=8, help="independent estimates per Mitsuba meter")
    ap.add_argument("--disk-radius", type=float, default=1e-4, help="radius of the meters' disks (m)")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument(
        "--integrator",
        default="path",
        choices=["path", "ptracer"],
        help="Mitsuba's integrator for the meters: path samples directions from the meter (no "
        "next-event estimation there: the direct light of a small emitter is a rare event); "
        "ptracer connects every light-path vertex to the meter but is biased for irradiance "
        "meters in Mitsuba 3.9.1 (see the module docs)",
    )
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("-o", "--out", required=True, help="Markdown table")
    a = ap.parse_args(argv)
    work = Path(a.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    t_lx, sensors = luxest(a, work)
    lit = [(i, s) for i, s in enumerate(sensors) if s[2] > 0 and s[3] > 0]
    lx_time = {i: t_lx * (s[3] / s[2] / TARGET) ** 2 for i, s in lit}
    # The backward estimate costs each sensor its own samples (about the same per sample): a
    # sensor reaches 1 % at (t / sensors) · (r_i / 0.01)², every sensor at the sum of those.
    t_ga, backward = gather(a, work)
    ga_time = {i: t_ga / len(backward) * (backward[i][1] / backward[i][0] / TARGET) ** 2 for i, _ in lit}

    import drjit as dr
    import mitsuba as mi
    import numpy as np

    mi.set_variant(a.variant)
    xml = scene_xml(mi, a.mitsuba_scene, integrator=a.integrator)
    # Mitsuba's parser merges identical nested objects, and a meter can belong to one shape only:
    # the sample counts differ by one per meter (spp + i) to keep the meters distinct.
    meters = "".join(meter_xml(i, s[0], s[1], a.disk_radius, a.spp + i) for i, s in lit)
    xml = xml.replace("</scene>", meters + "</scene>")
    scene = mi.load_string(xml.replace("$spp", "1"))
    index = {s.id(): k for k, s in enumerate(scene.sensors())}
    mi_time, mi_value, mi_se = {}, {}, {}
    for i, s in lit:
        k = index[f"meter{i}_sensor"]
        dr.eval(mi.render(scene, sensor=k, spp=16, seed=0))  # JIT warm-up for this sensor
        # Independent estimates (the meter's film is one pixel): replicates with their own seeds.
        t0 = time.process_time()
        y = []
        for r in range(a.replicates):
            # spp given every time: a render with spp sets the sensor's sample count for good
            # (the warm-up's 16 were what every replicate used before this was noticed).
            img = mi.render(scene, sensor=k, seed=1 + r + a.replicates * i, spp=a.spp)
            dr.eval(img)
            y.append(float(luminance(np.array(img).reshape(-1)[:3])))
        cpu = time.process_time() - t0
        y = np.array(y)
        mean, rel = y.mean(), y.std(ddof=1) / y.mean() if y.mean() > 0 else float("inf")
        # One pixel's estimate has relative error `rel` for spp samples: 1 % needs (rel/0.01)² x.
        mi_time[i] = cpu / a.replicates * (rel / TARGET) ** 2
        mi_value[i] = mean
        mi_se[i] = y.std(ddof=1) / np.sqrt(len(y))
    rows = sorted(lit, key=lambda t: lx_time[t[0]])
    lx_all, mi_all = max(lx_time.values()), sum(mi_time.values())
    lx_med = statistics.median(lx_time.values())
    mi_med = statistics.median(mi_time.values())
    ga_all, ga_med = sum(ga_time.values()), statistics.median(ga_time.values())
    speedups = sorted(mi_time[i] / lx_time[i] for i, _ in lit)
    z = {i: (mi_value[i] - s[2]) / (mi_se[i] ** 2 + s[3] ** 2) ** 0.5 for i, s in lit}
    lines = [
        f"Sensors at 1 % standard error: `{a.scene}`, {len(lit)} lit sensors of {len(sensors)}; luxest `estimate sensors` "
        f"{a.paths} paths ({t_lx:.1f} CPU-s), Mitsuba 3 `{a.variant}` `{a.integrator}` irradiance meters (disk radius {a.disk_radius:g} m, "
        f"{a.replicates} x {a.spp} samples each) ({time.strftime('%Y-%m-%d %H:%M')}; {host_summary()}).",
        "",
        f"luxest `estimate gather` (backward estimate) {a.gather_samples} samples per sensor ({t_ga:.1f} CPU-s).",
        "",
        "| | luxest local estimate | luxest backward estimate | Mitsuba 3 irradiance meters |",
        "|---|---|---|---|",
        f"| every lit sensor at 1 % | {lx_all:.1f} CPU-s (one run, the slowest sensor) | {ga_all:.2f} CPU-s (per sensor, summed) "
        f"| {mi_all:.1f} CPU-s (one render per sensor, summed) |",
        f"| median sensor at 1 % | {lx_med:.2f} CPU-s | {ga_med:.4f} CPU-s | {mi_med:.2f} CPU-s |",
        "",
        f"Per sensor, Mitsuba's time / luxest's time to 1 %: median {statistics.median(speedups):.1f}, "
        f"lowest {speedups[0]:.2f}, highest {speedups[-1]:.1f}. Mitsuba's value / luxest's: median "
        f"{statistics.median(mi_value[i] / s[2] for i, s in lit):.4f}; z = (Mitsuba − luxest) / combined standard "
        f"error: max abs {max(abs(v) for v in z.values()):.2f}, mean z² {sum(v * v for v in z.values()) / len(z):.2f} "
        f"(the two agree when mean z² is near 1; Mitsuba's standard errors come from {a.replicates} replicates).",
        "",
        "| sensor | luxest E | rel. SE | Mitsuba / luxest | z | luxest CPU-s to 1 % | backward CPU-s to 1 % | Mitsuba CPU-s to 1 % |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {i} | {s[2]:.4g} | {s[3] / s[2]:.2e} | {mi_value[i] / s[2]:.4f} | {z[i]:+.2f} | {lx_time[i]:.3f} | "
        f"{ga_time[i]:.4f} | {mi_time[i]:.3f} |"
        for i, s in rows
    ]
    write_text(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines[:8]))


if __name__ == "__main__":
    main()
