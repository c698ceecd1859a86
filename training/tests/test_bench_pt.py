"""pipelines/bench_pt.py: the report names, for each target relMSE, the Mitsuba sampler that needs
the least CPU time, and divides luxest's time by that sampler's; pipelines/mitsuba_render.py puts
the chosen sampler in place of the exported one."""

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "pipelines"))
import bench_pt  # noqa: E402
import mitsuba_render  # noqa: E402

SAMPLERS = ["independent", "stratified", "ldsampler", "multijitter"]


def table():
    """CPU-s to each target: Mitsuba path's best sampler differs between the targets."""
    lo, hi = bench_pt.TARGETS
    cpu = {
        ("luxest trace", lo): 0.6,
        ("luxest trace", hi): 4.8,
        ("luxest light tracer", lo): 1.8,
        ("luxest light tracer", hi): 17.0,
    }
    path = {"independent": (0.65, 6.0), "stratified": (0.40, 3.6), "ldsampler": (0.45, 3.5), "multijitter": (0.5, 3.2)}
    ptracer = {
        "independent": (1.0, 9.0),
        "stratified": (0.9, 10.0),
        "ldsampler": (1.2, 12.0),
        "multijitter": (1.4, 10.0),
    }
    for integrator, times in (("path", path), ("ptracer", ptracer)):
        for sm, (a, b) in times.items():
            cpu[bench_pt.mitsuba_name(integrator, sm), lo] = a
            cpu[bench_pt.mitsuba_name(integrator, sm), hi] = b
    return cpu


def test_best_sampler_is_the_fastest_to_each_target():
    lo, hi = bench_pt.TARGETS
    cpu = table()
    assert bench_pt.best_sampler(cpu, "path", SAMPLERS, lo) == "stratified"
    assert bench_pt.best_sampler(cpu, "path", SAMPLERS, hi) == "multijitter"
    assert bench_pt.best_sampler(cpu, "ptracer", SAMPLERS, hi) == "independent"


def test_ratios_divide_by_the_best_sampler_and_name_the_host_target():
    lines = bench_pt.at_its_best(table(), SAMPLERS, "AMD EPYC, 2 CPUs, AVX-512")
    trace = next(x for x in lines if x.startswith("luxest trace / Mitsuba path at its best"))
    # 0.6 / 0.40 and 4.8 / 3.2; the AVX-512 target is 1.0.
    assert "1.50 at 0.01 (stratified), 1.50 at 0.001 (multijitter)" in trace
    assert "at most 1 on this AVX-512 host" in trace
    each = next(x for x in lines if x.startswith("luxest trace / Mitsuba path with each sampler"))
    assert "independent 0.80, stratified 1.33, ldsampler 1.37, multijitter 1.50" in each
    lt = next(x for x in lines if x.startswith("luxest light tracer / Mitsuba ptracer at its best"))
    assert "2.00 at 0.01 (stratified), 1.89 at 0.001 (independent)" in lt
    avx2 = bench_pt.at_its_best(table(), SAMPLERS, "Intel Xeon, 8 CPUs, AVX2 (no AVX-512)")
    assert any("at most 0.5 on this AVX2 host" in x for x in avx2)
    # A scene with its own target (the office, the daylit room: 0.5) names it instead.
    office = bench_pt.at_its_best(table(), SAMPLERS, "AMD EPYC, 2 CPUs, AVX-512", 0.5)
    trace = next(x for x in office if x.startswith("luxest trace / Mitsuba path at its best"))
    assert trace.endswith("The target at 0.001 on this scene: at most 0.5.")


class FakeResolver:
    def prepend(self, path):
        self.path = path


class FakeMitsuba:
    def __init__(self):
        self.resolver = FakeResolver()

    def file_resolver(self):
        return self.resolver


def test_scene_xml_swaps_the_sampler_and_the_integrator(tmp_path):
    xml = tmp_path / "scene.xml"
    xml.write_text(
        '<scene><integrator type="path"><integer name="max_depth" value="-1"/></integrator><sensor><film><integer name="width" value="512"/>'
        '<integer name="height" value="512"/></film>'
        '<sampler type="independent"><integer name="sample_count" value="16"/></sampler></sensor></scene>'
    )
    out = mitsuba_render.scene_xml(FakeMitsuba(), str(xml), "64x32", "ptracer", "multijitter")
    assert '<sampler type="multijitter">' in out and "independent" not in out
    assert '<integrator type="ptracer">' in out
    assert '"width" value="64"' in out and '"height" value="32"' in out
    # The default keeps the exported sampler.
    assert '<sampler type="independent">' in mitsuba_render.scene_xml(FakeMitsuba(), str(xml))
    # A scene without the exported sampler cannot take another: an error, not a silent default.
    xml.write_text('<scene><integrator type="path"/></scene>')
    with pytest.raises(SystemExit, match="no <sampler"):
        mitsuba_render.scene_xml(FakeMitsuba(), str(xml), None, "path", "ldsampler")


def test_trace_variant_parses_label_and_arguments():
    assert bench_pt.trace_variant("power=--light-sampler power") == (
        "luxest trace, power",
        ["--light-sampler", "power"],
    )
    assert bench_pt.trace_variant("no-portals=--portals off")[1] == ["--portals", "off"]
    for bad in ("power", "=--portals off", "power=", "two words=--x y"):
        with pytest.raises(bench_pt.argparse.ArgumentTypeError):
            bench_pt.trace_variant(bad)


def test_variant_rows_are_compared_with_mitsuba_and_with_the_main_trace():
    lo, hi = bench_pt.TARGETS
    cpu = table()
    name, _ = bench_pt.trace_variant("power=--light-sampler power")
    cpu[name, lo], cpu[name, hi] = 1.2, 6.4
    assert bench_pt.trace_rows(cpu) == ["luxest trace", name]
    lines = bench_pt.at_its_best(cpu, SAMPLERS, "AMD EPYC, 2 CPUs, AVX-512")
    row = next(x for x in lines if x.startswith(f"{name} / Mitsuba path at its best"))
    # 1.2 / 0.40 (stratified) and 6.4 / 3.2 (multijitter); the host target only on the main row.
    assert "3.00 at 0.01 (stratified), 2.00 at 0.001 (multijitter)" in row
    assert "at most" not in row
    main = bench_pt.against_variants(cpu)
    # 0.6 / 1.2 and 4.8 / 6.4.
    assert main[0] == f"luxest trace / {name}, CPU time to equal relMSE: 0.50 at 0.01, 0.75 at 0.001."
    assert bench_pt.against_variants(table()) == []


def test_variants_are_rendered_interleaved_with_their_arguments(tmp_path):
    """main() with a stand-in trace and evaluate: each variant row renders at every budget and
    repetition in turn with the main row, with its extra arguments, and reaches the report."""
    log = tmp_path / "calls.txt"
    trace = tmp_path / "trace"
    trace.write_text(
        "#!/bin/sh\n"
        f'echo "$*" >> {log}\n'
        # Some CPU time to divide by.
        "i=0; while [ $i -lt 20000 ]; do i=$((i + 1)); done\n"
    )
    evaluate = tmp_path / "evaluate"
    # Scores every image: relMSE 1e-2 for the main row, 2e-2 for the variant.
    evaluate.write_text(
        "#!/bin/sh\n"
        'out=""; prev=""; imgs=""\n'
        'for x in "$@"; do [ "$prev" = "-o" ] && out="$x"; prev="$x"; done\n'
        'echo image,rel_mse > "$out"\n'
        'for x in "$@"; do case "$x" in *trace_v1*) echo "$x,2e-2" >> "$out";; *trace_r*) echo "$x,1e-2" >> "$out";; esac; done\n'
    )
    trace.chmod(0o755)
    evaluate.chmod(0o755)
    out = tmp_path / "pt.md"
    bench_pt.main(
        [
            "--scene", str(tmp_path / "scene.lxs"), "--reference", str(tmp_path / "ref.exr"),
            "--trace", str(trace), "--estimate", "/bin/false", "--evaluate", str(evaluate),
            "--resolution", "4x2", "--spp", "1,4", "--trace-variant", "power=--light-sampler power",
            "--work-dir", str(tmp_path / "runs"), "-o", str(out),
        ]
    )  # fmt: skip
    calls = log.read_text().splitlines()
    # rep 1: budget 1 main, variant; budget 4 main, variant; then rep 2 likewise.
    assert [("--light-sampler power" in c, c.split("--spp ")[1].split()[0]) for c in calls] == [
        (False, "1"), (True, "1"), (False, "4"), (True, "4"),
    ] * 2  # fmt: skip
    text = out.read_text()
    assert "| luxest trace, power | 4 spp |" in text
    assert "luxest trace / luxest trace, power, CPU time to equal relMSE:" in text
