#!/usr/bin/env python3
"""`make bench-denoise` (part of `make bench`): CPU seconds of luxest's `denoise` and of Intel Open
Image Denoise (pipelines/oidn_denoise.py, the peer) on the same inputs in the same run,
interleaved.

The inputs are one snapshot of `make eval`'s Cornell box (hdr and every feature the model takes)
at its own size and tiled to SIDE² (default 1024²). Each command runs as a whole process, as a
user calls it (model or library load included); its CPU seconds are the process's (user +
system, all threads, from the kernel: `getrusage(RUSAGE_CHILDREN)`). Rounds alternate which
denoiser goes first. The marginal cost per megapixel — (median CPU-s on the large image − median
on the small one) / (the difference in megapixels) — cancels what does not grow with the image
(start-up, model load, file names); the inference criterion compares it (luxest's over OIDN's).
Any denoiser honouring the `denoise` command line can be measured (`--denoise`, `DENOISE=` in
make). More peers with oidn_denoise.py's command line (`--peer NAME=COMMAND`, repeated: OIDN
2.5.1 at quality high with clean and with prefiltered features in `make bench-denoise`) run in the
same rounds, each a row and a ratio.

Output: a Markdown table (`-o`) with a row per denoiser and the peer's column kept, and a CSV
beside it (`.csv`)."""

import argparse
import csv
import resource
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
import luxest_contract as contract  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from host import host_summary  # noqa: E402


def fail(message):
    print(f"bench_denoise: error: {message}", file=sys.stderr)
    sys.exit(1)


def prepare(hdr_path, kinds, side, work):
    """Copies of the snapshot `hdr_path` and its feature images (`kinds`, named as aov-write
    names them) into work/small/ and, tiled to side², work/large/, each source read once;
    returns ({size: hdr path}, {size: megapixels})."""
    parsed = contract.parse_image_name(Path(hdr_path).name)
    if parsed is None or parsed.kind != "hdr" or parsed.reference:
        fail(f"{hdr_path}: not a noisy image `<name>_<count>spp.hdr.exr` (or `le`)")
    sizes = ("small", "large")
    for size_dir in sizes:
        (work / size_dir).mkdir(parents=True, exist_ok=True)
    mp = {}
    for kind in ("hdr",) + tuple(kinds):
        src = Path(hdr_path).with_name(contract.image_name(parsed.name, kind, parsed.spp, parsed.unit))
        if not src.is_file():
            fail(f"{src}: missing (make eval renders the Cornell box's snapshots and features)")
        image = contract.read(src)
        h, w, _ = image.pixels.shape
        large = np.tile(image.pixels, (-(-side // h), -(-side // w), 1))[:side, :side]
        for size_dir, px in zip(sizes, (image.pixels, large)):
            contract.write(work / size_dir / src.name, px, image.header)
            if kind == "hdr":
                mp[size_dir] = px.shape[0] * px.shape[1] / 1e6
    return {s: work / s / Path(hdr_path).name for s in sizes}, mp


def run(cmd):
    """(CPU seconds, wall seconds) of one command run to completion; exit 1 with its message if
    it fails."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        fail(f"{cmd[0]}: cannot run it ({e.strerror})")
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode != 0:
        said = (r.stderr or r.stdout).strip().splitlines()
        fail(f"{shlex.join(cmd)} failed (exit {r.returncode}){': ' + said[-1] if said else ''}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def commands(denoise, model, oidn, hdr, out_dir, kinds, peers=()):
    """The command lines for one input: luxest's `denoise`, the OIDN peer and the further peers
    (name, command), by name."""
    parsed = contract.parse_image_name(hdr.name)
    feature = lambda kind: str(hdr.with_name(contract.image_name(parsed.name, kind, parsed.spp, parsed.unit)))
    luxest = shlex.split(denoise) + [
        str(hdr),
        "--model",
        str(model),
        "-o",
        str(out_dir / f"luxest-{hdr.parent.name}.dn.exr"),
    ]
    peer = lambda name, cmd: (
        shlex.split(cmd)
        + [
            str(hdr),
            "--alb",
            feature("alb"),
            "--nrm",
            feature("nrm"),
            "-o",
            str(out_dir / f"{name}-{hdr.parent.name}.dn.exr"),
        ]
    )
    return {"luxest": luxest, "oidn": peer("oidn", oidn), **{name: peer(name, cmd) for name, cmd in peers}}


def marginal(small, large, mp_small, mp_large):
    """Seconds per megapixel from the medians on two image sizes."""
    return (statistics.median(large) - statistics.median(small)) / (mp_large - mp_small)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--input", required=True, help="a Cornell snapshot `<name>_<spp>spp.hdr.exr` of make eval")
    ap.add_argument("--features", default="alb,nrm,emi,ema", help="the feature kinds the model takes")
    ap.add_argument("--model", required=True)
    ap.add_argument("--denoise", required=True, help="luxest's denoise command")
    ap.add_argument("--oidn", required=True, help="the peer's command (pipelines/oidn_denoise.py)")
    ap.add_argument(
        "--peer",
        action="append",
        default=[],
        metavar="NAME=COMMAND",
        help="a further peer with oidn_denoise.py's command line (repeatable)",
    )
    ap.add_argument("--side", type=int, default=1024, help="side of the large (tiled) image")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("-o", "--out", required=True, help="Markdown table; the CSV goes beside it")
    args = ap.parse_args(argv)
    if args.rounds < 1 or args.side < 64:
        fail(f"--rounds {args.rounds} / --side {args.side}: expected at least 1 round and a side of 64")
    out, work = Path(args.out), Path(args.work_dir)
    out_csv = out.with_suffix(".csv")
    if out.suffix == ".csv":
        fail(f"{out}: the Markdown table's name (the CSV goes beside it as {out_csv.name})")
    for p in (out, out_csv):
        if p.resolve() == Path(args.input).resolve() or (p.exists() and not p.is_file()):
            fail(f"{p}: not a file this benchmark may write")
    if Path(args.input).resolve().parent in ((work / "small").resolve(), (work / "large").resolve()):
        fail(f"{args.input}: inside the work directory, whose copies would overwrite it")
    peers = []
    for p in args.peer:
        name, sep, cmd = p.partition("=")
        if not sep or not name or not cmd.strip() or name in ("luxest", "oidn") or name in dict(peers):
            fail(f"--peer {p!r}: expected NAME=COMMAND with a new name (not luxest or oidn)")
        peers.append((name, cmd))
    names = ["luxest", "oidn"] + [n for n, _ in peers]
    kinds = [k for k in args.features.split(",") if k]
    inputs, mp = prepare(args.input, kinds, args.side, work)
    if mp["large"] <= mp["small"]:
        fail(f"--side {args.side}: the large image must be larger than the input")
    cpu = {(d, s): [] for d in names for s in inputs}
    wall = {(d, s): [] for d in names for s in inputs}
    for r in range(args.rounds):
        for size, hdr in inputs.items():
            cmds = commands(args.denoise, args.model, args.oidn, hdr, work, kinds, peers)
            order = names if r % 2 == 0 else names[::-1]
            for d in order:
                c, w = run(cmds[d])
                cpu[(d, size)].append(c)
                wall[(d, size)].append(w)
    rows = []
    for d in names:
        rows.append(
            {
                "denoiser": d,
                "cpu_s_small": statistics.median(cpu[(d, "small")]),
                "cpu_s_large": statistics.median(cpu[(d, "large")]),
                "wall_s_large": statistics.median(wall[(d, "large")]),
                "cpu_s_per_megapixel": marginal(cpu[(d, "small")], cpu[(d, "large")], mp["small"], mp["large"]),
                "wall_s_per_megapixel": marginal(wall[(d, "small")], wall[(d, "large")], mp["small"], mp["large"]),
            }
        )
    ratio = rows[0]["cpu_s_per_megapixel"] / rows[1]["cpu_s_per_megapixel"]
    tmp_csv = out_csv.with_name(out_csv.name + ".tmp")
    with open(tmp_csv, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)
    small_side = round((mp["small"] * 1e6) ** 0.5)
    lines = [
        f"# Denoiser inference: luxest against Intel Open Image Denoise ({Path(args.input).name})",
        "",
        f"Whole processes on {host_summary()}, {args.rounds} interleaved rounds, medians; CPU seconds = "
        "user + system of the process (all threads). Per megapixel: the marginal cost between the "
        f"{small_side}² input and its {args.side}² tiling (start-up and model load cancel).",
        "",
        f"| denoiser | CPU-s, {small_side}² | CPU-s, {args.side}² | wall s, {args.side}² | CPU-s per megapixel | wall s per megapixel |",
        "|---|---|---|---|---|---|",
    ]
    for row in rows:
        label = {"luxest": f"luxest `denoise` ({Path(args.model).name})", "oidn": "OIDN 1.4.3 (peer)"}.get(
            row["denoiser"], f"{row['denoiser']} (peer)"
        )
        lines.append(
            f"| {label} | {row['cpu_s_small']:.2f} | {row['cpu_s_large']:.2f} | {row['wall_s_large']:.2f} | "
            f"{row['cpu_s_per_megapixel']:.2f} | {row['wall_s_per_megapixel']:.2f} |"
        )
    lines += ["", f"luxest / OIDN, CPU-s per megapixel: {ratio:.2f}", ""]
    for row in rows[2:]:
        lines += [
            f"luxest / {row['denoiser']}, CPU-s per megapixel: "
            f"{rows[0]['cpu_s_per_megapixel'] / row['cpu_s_per_megapixel']:.2f}",
            "",
        ]
    tmp_md = out.with_name(out.name + ".tmp")
    tmp_md.write_text("\n".join(lines))
    tmp_csv.replace(out_csv)
    tmp_md.replace(out)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
