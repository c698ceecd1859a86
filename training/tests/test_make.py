"""The Make rules' data flow (`make -n`, nothing is run): seeds of the dataset and of make eval,
the noisy target following NOISY_MAX, and every stage called through its variable; and one real
make run with a stand-in denoiser (make eval's model stamp)."""

import atexit
import functools
import os
import re
import shlex
import shutil
import subprocess
import tempfile
from pathlib import Path

import luxest_contract as contract

ROOT = Path(__file__).resolve().parents[2]
# Stand-in stage programs: files make sees as up-to-date prerequisites (no cargo build planned).
_STAGE_DIR = Path(tempfile.mkdtemp(prefix="luxest-stages-"))
atexit.register(shutil.rmtree, _STAGE_DIR, True)
STAGES = {
    v: str(_STAGE_DIR / v.lower())
    for v in ("SCENE_COMPILE", "TRACE", "AOV_WRITE", "ESTIMATE", "DENOISE", "EVALUATE", "OIDN_DENOISE")
}
for _p in STAGES.values():
    Path(_p).touch()


def make(*args, **variables):
    """make with every stage replaced by a path that does not exist as a make target (so no cargo
    build is planned), a dataset that does not exist and make eval's directory in a temporary one
    (make eval writes its model stamp even in a dry run); `variables` override these. A dry run
    (`-n`) is made once per session for each command line (every make reads all the pipeline's
    makefiles, a second or two: several tests ask for the same plan)."""
    v = {**STAGES, "DATASET": "pytest-dry-run", "EVAL_DIR": str(_STAGE_DIR / "eval"), "EVAL_OIDN2": "yes", **variables}
    command = ("make", "--no-print-directory", *args, *(f"{k}={val}" for k, val in v.items()))
    return _dry_run(command) if "-n" in args else _run(command)


def _run(command):
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True)


@functools.cache
def _dry_run(command):
    return _run(command)


def dry_run(*targets, **variables):
    """The stage commands `make -n` would run (see `make`)."""
    r = make("-n", *targets, **variables)
    assert r.returncode == 0, r.stderr
    return [shlex.split(line) for line in r.stdout.splitlines() if line.startswith(str(_STAGE_DIR))]


def flag(cmd, name):
    return cmd[cmd.index(name) + 1]


def test_dataset_references_have_their_own_seed_and_features_share_traces():
    cmds = dry_run("reference", "noisy")
    traces = [c for c in cmds if c[0] == STAGES["TRACE"]]
    own_dir = f"/{contract.OWN_FEATURES_DIR}/"
    own = [c for c in cmds if c[0] == STAGES["AOV_WRITE"] and own_dir in flag(c, "-o")]
    aovs = [c for c in cmds if c[0] == STAGES["AOV_WRITE"] and c not in own]
    assert len(traces) == len(aovs) == 2 * 24  # quick: 24 scenes, a reference and a noisy run each
    ref_seeds = {flag(c, "--seed") for c in traces if "--reference" in c}
    noisy_seeds = {flag(c, "--seed") for c in traces if "--reference" not in c}
    assert len(ref_seeds) == len(noisy_seeds) == 1 and ref_seeds.isdisjoint(noisy_seeds)
    # The features at each level's own samples: one run per scene, the levels below FEATURE_SPP,
    # the noisy radiance's seed, --min-samples 1, into <split>/own/ under the scene's name.
    assert len(own) == 24 and all(flag(c, "--min-samples") == "1" for c in own)
    assert {(flag(c, "--seed"), flag(c, "--spp"), flag(c, "--snapshots")) for c in own} == {
        (*noisy_seeds, "8", "1,2,4,8")
    }
    assert sorted(Path(flag(c, "-o")).name for c in own) == sorted(
        Path(flag(c, "-o")).name for c in traces if "--reference" not in c
    )
    # aov-write gets exactly trace's arguments for each image set (same seed, spp, snapshots),
    # and the features' least samples per pixel.
    assert all(flag(c, "--min-samples") == "16" for c in aovs)
    assert sorted(c[1:] for c in traces) == sorted([a for a in c[1:] if a not in ("--min-samples", "16")] for c in aovs)


def test_features_follow_feature_spp():
    # The stamp named after FEATURE_SPP is a prerequisite of every feature set and of no
    # radiance (changing it re-renders only the features), and aov-write is told it; make eval's
    # Cornell-box features too.
    out = make("-n", "-p", "reference", "noisy", FEATURE_SPP="32").stdout
    stamp = "build/dataset/pytest-dry-run/feature-spp-32"
    for level in ("ref", "001024spp"):
        nrm = re.search(rf"^data/pytest-dry-run/%_{level}\.nrm\.exr:(.*)$", out, re.M)
        hdr = re.search(rf"^data/pytest-dry-run/%_{level}\.hdr\.exr:(.*)$", out, re.M)
        assert nrm and stamp in nrm.group(1).split(), level
        assert hdr and stamp not in hdr.group(1).split() and "feature-spp" not in hdr.group(1), level
    cmds = dry_run("reference", "noisy", "eval", FEATURE_SPP="32", EVAL_MODEL="models/default.onnx")
    own_dir = f"/{contract.OWN_FEATURES_DIR}/"
    aovs = [c for c in cmds if c[0] == STAGES["AOV_WRITE"] and own_dir not in flag(c, "-o")]
    # (make eval also renders the features of each snapshot's own samples, --min-samples 1, in
    # own-features/ directories, and the public interiors' reference albedo at full samples.)
    own_eval = [c for c in aovs if "/own-features/" in flag(c, "-o")]
    aovs = [c for c in aovs if c not in own_eval and not ("--reference" in c and "/public/" in flag(c, "-o"))]
    assert own_eval and all(flag(c, "--min-samples") == "1" for c in own_eval)
    assert any("cornell-box" in c[1] for c in aovs) and all(flag(c, "--min-samples") == "32" for c in aovs)
    # The features at each level's own samples: the levels below FEATURE_SPP.
    own = [c for c in cmds if c[0] == STAGES["AOV_WRITE"] and own_dir in flag(c, "-o")]
    assert own and {flag(c, "--snapshots") for c in own} == {"1,2,4,8,16"}
    assert not [c for c in cmds if c[0] == STAGES["TRACE"] and "--min-samples" in c]
    # The main job's features too.
    run = [c for c in dry_run("run", FEATURE_SPP="32") if c[0] == STAGES["AOV_WRITE"]]
    assert len(run) == 1 and flag(run[0], "--min-samples") == "32"


def test_local_estimate_family_renders_train_and_valid_scenes_with_the_noisy_seed():
    cmds = dry_run("noisy", DATASET_DLE="100 1000")
    traces = [c for c in cmds if c[0] == STAGES["TRACE"]]
    dle = [c for c in cmds if c[0] == STAGES["ESTIMATE"] and c[1] == "image"]
    # quick: 24 scenes, 4 of them test scenes (make eval renders theirs)
    assert len(dle) == 2 * 20 and not [c for c in dle if "/test/" in c[2]]
    assert {flag(c, "--paths") for c in dle} == {"100", "1000"}
    assert {flag(c, "--seed") for c in dle} == {flag(traces[0], "--seed")}
    assert all(re.search(r"/(train|valid)/gen\d{4}_00(0100|1000)le\.hdr\.exr$", flag(c, "-o")) for c in dle)
    # Training is told which light-path counts to use.
    r = make("-n", "-W", "training/train.py", "models/pytest-dry-run.onnx", DATASET_DLE="100 1000")
    lines = r.stdout.replace("\\\n", " ").splitlines()
    runs = [shlex.split(line.split("&&", 1)[1]) for line in lines if "preprocess.py" in line or "train.py" in line]
    assert len(runs) == 2 and all(
        c[c.index("--dle-paths") + 1 : c.index("--dle-paths") + 3] == ["100", "1000"] for c in runs
    )
    # And which loss (TRAIN_LOSS, l1 unless set).
    assert [c[c.index("--loss") + 1] for c in runs if "train.py" in c] == ["l1"]
    r = make("-n", "-W", "training/train.py", "models/pytest-dry-run.onnx", TRAIN_LOSS="psnr")
    lines = r.stdout.replace("\\\n", " ").splitlines()
    train = [shlex.split(line.split("&&", 1)[1]) for line in lines if "train.py" in line]
    assert len(train) == 1 and train[0][train[0].index("--loss") + 1] == "psnr"


def test_references_follow_ref_spp():
    # The stamp named after REF_SPP is a prerequisite of every reference.
    out = make("-n", "-p", "reference", REF_SPP="2048").stdout
    for kind in ("hdr", "nrm"):
        rule = re.search(rf"^data/pytest-dry-run/%_ref\.{kind}\.exr:(.*)$", out, re.M)
        assert rule and "build/dataset/pytest-dry-run/reference-spp-2048" in rule.group(1).split(), kind
    cmds = dry_run("reference", REF_SPP="2048")
    assert all(flag(c, "--spp") == "2048" for c in cmds if c[0] == STAGES["TRACE"])


def test_scenes_follow_dataset_side():
    # The stamp named after DATASET_SIDE is a prerequisite of every generated scene, and the
    # generator is told the side.
    out = make("-n", "-p", "reference", DATASET_SIDE="96")
    assert out.returncode == 0, out.stderr
    rule = re.search(r"^build/dataset/pytest-dry-run/scenes/%\.ron:(.*)$", out.stdout, re.M)
    assert rule and "build/dataset/pytest-dry-run/side-96" in rule.group(1).split()
    gen = [shlex.split(line) for line in out.stdout.splitlines() if line.startswith("python3 data-gen/generate.py")]
    scenes = [c for c in gen if flag(c, "--only") == "scenes"]
    assert scenes and all(flag(c, "--side") == "96" and flag(c, "--preset") == "quick" for c in scenes)


def test_compiled_scenes_depend_on_the_texture_library():
    # Every compiled scene depends on every image of the library (a compiled scene holds its
    # textures' pixels); the images are written by one generator run, the rule of a stamp that
    # depends on the generator and the library's code, not on the image side.
    out = make("-n", "-p", "dataset-scenes", DATASET_SIDE="96")
    assert out.returncode == 0, out.stderr
    images = subprocess.run(
        ["python3", "data-gen/generate.py", "--list-textures"], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.split()
    assert len(images) >= 8
    rule = re.search(r"^build/dataset/pytest-dry-run/%\.lxs:(.*)$", out.stdout, re.M)
    assert rule and {f"build/dataset/pytest-dry-run/scenes/{i}" for i in images} <= set(rule.group(1).split())
    stamp = re.search(r"^build/dataset/pytest-dry-run/textures\.stamp:(.*)$", out.stdout, re.M)
    assert stamp and set(stamp.group(1).split()) == {"data-gen/generate.py", "data-gen/textures.py"}
    writes = [
        line
        for line in out.stdout.splitlines()
        if line.startswith("python3 data-gen/generate.py") and "--only textures" in line
    ]
    assert writes and all("--side" not in line for line in writes)


def test_textured_example_runs_every_stage_through_its_variable():
    # make textured-example: trace, aov-write, denoise (the committed model) and estimate image
    # on the compiled scenes/textured-room.ron.
    cmds = dry_run("textured-example")
    scene = "build/textured-room/scene.lxs"
    assert [c[0] for c in cmds] == [STAGES[v] for v in ("SCENE_COMPILE", "TRACE", "AOV_WRITE", "DENOISE", "ESTIMATE")]
    assert cmds[0][1] == "scenes/textured-room.ron" and all(scene in c for c in (cmds[1], cmds[2], cmds[4]))
    assert flag(cmds[3], "--model") == "models/default.onnx" and cmds[4][1] == "image"


def test_generator_writes_the_side_it_is_given(tmp_path):
    subprocess.run(
        [
            "python3",
            "data-gen/generate.py",
            "--preset",
            "quick",
            "--side",
            "72",
            "--out",
            str(tmp_path),
            "--only",
            "scenes",
        ],
        cwd=ROOT,
        check=True,
        capture_output=True,
    )
    scenes = sorted(tmp_path.glob("*/gen*.ron"))
    assert len(scenes) == 24 and all("resolution: (72, 72)" in p.read_text() for p in scenes)
    r = subprocess.run(
        ["python3", "data-gen/generate.py", "--preset", "quick", "--out", str(tmp_path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert r.returncode != 0 and "--side" in r.stderr


def test_dataset_count_adds_scenes_and_keeps_the_smaller_datasets(tmp_path):
    # DATASET_COUNT reaches the generator; scene i is the same text whatever the count, and
    # every sixth scene (index 5 mod 6) is a test scene, so held-out scenes stay held out.
    traced = {flag(c, "-o") for c in dry_run("reference", DATASET_COUNT="30") if c[0] == STAGES["TRACE"]}
    assert len(traced) == 30 and "data/pytest-dry-run/test/gen0029" in traced
    assert len({flag(c, "-o") for c in dry_run("reference") if c[0] == STAGES["TRACE"]}) == 24
    for n in (24, 30):
        subprocess.run(
            ["python3", "data-gen/generate.py", "--scenes", str(n), "--side", "32", "--only", "scenes"]
            + ["--out", str(tmp_path / str(n))],
            cwd=ROOT,
            check=True,
            capture_output=True,
        )
    small = sorted(p.relative_to(tmp_path / "24") for p in (tmp_path / "24").glob("*/*.ron"))
    large = sorted(p.relative_to(tmp_path / "30") for p in (tmp_path / "30").glob("*/*.ron"))
    assert len(small) == 24 and len(large) == 30 and set(small) < set(large)
    assert all((tmp_path / "24" / p).read_text() == (tmp_path / "30" / p).read_text() for p in small)
    assert sorted(p.stem for p in (tmp_path / "30" / "test").glob("*.ron")) == [
        f"gen{i:04d}" for i in range(30) if i % 6 == 5
    ]
    r = subprocess.run(
        ["python3", "data-gen/generate.py", "--scenes", "5", "--list"], cwd=ROOT, capture_output=True, text=True
    )
    assert r.returncode != 0 and "--scenes 5" in r.stderr


def test_noisy_target_follows_noisy_max():
    cmds = dry_run("noisy", NOISY_LEVELS="1 2 4 8")
    runs = [c for c in cmds if c[0] == STAGES["TRACE"]]
    assert runs and all(flag(c, "--spp") == "8" and flag(c, "--snapshots") == "1,2,4,8" for c in runs)
    out = make("-n", "-p", "noisy", NOISY_LEVELS="1 2 4 8").stdout
    assert re.search(r"^data/pytest-dry-run/%_000008spp\.nrm\.exr:", out, re.M)


def test_eval_scores_the_trained_model_by_default():
    # `make reference noisy train eval`: every image make eval denoises, the Cornell box's and
    # the held-out scenes', goes through the model make train writes (a per-scene rule once
    # expanded it before it was defined and ran `denoise --model` with no model).
    cmds = dry_run("eval")
    denoised = [c for c in cmds if c[0] == STAGES["DENOISE"]]
    assert any("/dataset/" in flag(c, "-o") for c in denoised) and any(
        "/cornell-box/" in flag(c, "-o") for c in denoised
    )
    assert {flag(c, "--model") for c in denoised} == {"models/pytest-dry-run.onnx"}


def test_a_model_named_on_the_command_line_is_not_retrained(tmp_path):
    # `make eval EVAL_MODEL=<the model make train writes>` scores that file as it is, even when
    # training/*.py is newer (it once retrained it, overwriting a run); plain `make eval` and
    # `make train eval` still train it.
    model = tmp_path / "m.onnx"
    model.touch()
    os.utime(model, (0, 0))  # older than every training script

    def trains(*goals, **variables):
        r = make("-n", *goals, MODEL=model, **variables)
        assert r.returncode == 0, r.stderr
        return "train.py" in r.stdout

    assert not trains("eval", EVAL_MODEL=model)
    assert trains("eval")
    assert trains("train", "eval", EVAL_MODEL=model)


def test_eval_reference_is_independent_and_every_snapshot_is_denoised():
    cmds = dry_run("eval", EVAL_MODEL="models/default.onnx")
    traces = [c for c in cmds if c[0] == STAGES["TRACE"] and "cornell-box" in c[1]]
    ref = [c for c in traces if "--reference" in c]
    prog = [c for c in traces if "--reference" not in c]
    assert len(ref) == len(prog) == 1 and flag(ref[0], "--seed") != flag(prog[0], "--seed")
    snapshots = flag(prog[0], "--snapshots").split(",")
    denoised = [c for c in cmds if c[0] == STAGES["DENOISE"] and "/cornell-box/" in c[1]]
    # With the features of each snapshot's own samples (own-features/: each snapshot's own samples, the
    # powers of two) the same snapshots are denoised again, their features taken from there.
    default = [c for c in denoised if "/own-features/" in flag(c, "-o")]
    denoised = [c for c in denoised if c not in default]
    powers = [s for s in snapshots if int(s) & (int(s) - 1) == 0]
    assert sorted(int(re.search(r"_(\d{6})spp\.hdr\.exr$", c[1]).group(1)) for c in default) == sorted(map(int, powers))
    assert all("/own-features/" in flag(c, "--features-of") for c in default)
    assert all("--any-feature-samples" in c for c in default)
    images = [c for c in cmds if c[0] == STAGES["ESTIMATE"] and c[1] == "image" and "cornell-box" in c[2]]
    dle = [c for c in images if "--light-tracing" not in c]
    assert len(denoised) == len(snapshots) + len(dle)
    # The peers (Intel Open Image Denoise 1.4.3, and 2.5.1 through --oidn-lib at quality high)
    # denoise exactly the same inputs, with the same features.
    oidn = [c for c in cmds if c[0] == STAGES["OIDN_DENOISE"] and "/cornell-box/" in c[1]]
    assert sorted(c[1] for c in oidn) == sorted(c[1] for c in denoised + default)
    oidn2 = [c[c.index("--aux") + 2 :] + c[c.index("--aux") : c.index("--aux") + 2] for c in cmds if "--oidn-lib" in c]
    oidn2 = [c for c in oidn2 if "/cornell-box/" in c[0]]
    assert sorted(c[0] for c in oidn2) == sorted(c[1] for c in denoised + default)
    assert all(flag(c, "--aux") == ("prefilter" if "/own-features/" in flag(c, "-o") else "clean") for c in oidn2)
    assert {flag(c, "--alb") for c in oidn2} == {flag(c, "--alb") for c in oidn}
    # The double-local-estimate images are denoised with the features of one snapshot (those
    # its model takes, whichever they are: denoise --features-of).
    le = [c for c in denoised if re.search(r"le\.hdr\.exr$", c[1])]
    assert le and all(re.search(r"_\d{6}spp\.hdr\.exr$", flag(c, "--features-of")) for c in le)
    assert not any(f in c for c in le for f in ("--alb", "--nrm", "--emi", "--ema"))
    # The light-tracing baseline is scored as it is (not denoised), from the noisy seed.
    lt = [c for c in images if "--light-tracing" in c]
    assert lt and all(flag(c, "--seed") == flag(prog[0], "--seed") for c in lt)
    assert [c for c in cmds if c[0] == STAGES["EVALUATE"] and c[1] == "images"]
    # Every program run is a stage variable or the summary: no stage runs behind make's back.
    r = make("-n", "eval", EVAL_MODEL="models/default.onnx")
    others = [
        line
        for line in r.stdout.splitlines()
        if line.strip()
        and not line.startswith(
            (
                str(_STAGE_DIR),
                "mkdir",
                "python3 data-gen",
                "python3 pipelines/validate.py scene",
                ".venv/bin/python pipelines/eval.py",
                "\t",
            )
        )
    ]
    assert others == [], others


def test_held_out_references_follow_eval_heldout_ref_spp():
    # By default the held-out scenes are scored against the dataset's own references; with
    # EVAL_HELDOUT_REF_SPP make eval renders its own (that many samples, the reference seed, from
    # the dataset's compiled scene) and scores every held-out image against them.
    def plan(**v):
        cmds = dry_run("eval", EVAL_MODEL="models/default.onnx", **v)
        # (The dry-run dataset does not exist, so its own references are planned too: left out.)
        refs = [
            c
            for c in cmds
            if c[0] == STAGES["TRACE"]
            and "--reference" in c
            and not flag(c, "-o").startswith("data/")
            and "cornell-box" not in c[1]
            and "/public/" not in flag(c, "-o")
        ]
        scored = [c for c in cmds if c[0] == STAGES["EVALUATE"] and c[1] == "images" and "dataset-" in flag(c, "-o")]
        return refs, scored, cmds

    refs, scored, _ = plan()
    assert refs == [] and len(scored) == 4  # quick: 4 held-out scenes
    assert all(flag(c, "--reference").startswith("data/pytest-dry-run/test/") for c in scored)
    refs, scored, cmds = plan(EVAL_HELDOUT_REF_SPP="4096")
    assert len(refs) == len(scored) == 4
    noisy_seed = {flag(c, "--seed") for c in cmds if c[0] == STAGES["TRACE"] and "--reference" not in c}
    assert all(flag(c, "--spp") == "4096" and flag(c, "--seed") not in noisy_seed for c in refs)
    made = {flag(c, "-o") + "_ref.hdr.exr" for c in refs}
    assert {flag(c, "--reference") for c in scored} == made and all("/ref-4096/" in m for m in made)
    # The stamp is a prerequisite, not an image to score.
    assert not any("heldout-ref-spp" in a for c in scored for a in c)


def test_public_interiors_are_scored_with_independent_references_and_both_features():
    # make eval's public interiors (scenes/public/): each a reference with the reference seed, one
    # progressive run with the noisy seed, antialiased features beside it and of each snapshot's own samples
    # ones apart, every snapshot denoised by luxest and both OIDN releases, two reports a scene.
    cmds = dry_run("eval", EVAL_MODEL="models/default.onnx")
    names = ("living-room", "staircase")
    for name in names:
        traces = [c for c in cmds if c[0] == STAGES["TRACE"] and c[1] == f"build/public/{name}/scene.lxs"]
        ref = [c for c in traces if "--reference" in c]
        prog = [c for c in traces if "--reference" not in c]
        assert len(ref) == len(prog) == 1 and flag(ref[0], "--seed") != flag(prog[0], "--seed")
        assert flag(ref[0], "--resolution") == flag(prog[0], "--resolution")
        levels = flag(prog[0], "--snapshots").split(",")
        aovs = [c for c in cmds if c[0] == STAGES["AOV_WRITE"] and c[1] == f"build/public/{name}/scene.lxs"]
        noisy_aovs = [c for c in aovs if "--reference" not in c]
        assert sorted(flag(c, "--min-samples") == "1" for c in noisy_aovs) == [False, True]
        assert all(
            flag(c, "--seed") == flag(prog[0], "--seed") and flag(c, "--snapshots") == ",".join(levels)
            for c in noisy_aovs
        )
        snap = [c for c in cmds if c[0] == STAGES["DENOISE"] and f"/public/{name}/" in c[1] and "spp.hdr" in c[1]]
        assert len(snap) == 2 * len(levels)  # antialiased and own-sample features
        oidn = [c for c in cmds if c[0] == STAGES["OIDN_DENOISE"] and f"/public/{name}/" in c[1] and "spp.hdr" in c[1]]
        oidn2 = [
            c for c in cmds if "--oidn-lib" in c and f"/public/{name}/" in flag(c, "-o") and "spp.dn" in flag(c, "-o")
        ]
        assert len(oidn) == len(oidn2) == 2 * len(levels)
        reports = [c for c in cmds if c[0] == STAGES["EVALUATE"] and f"public-{name}" in flag(c, "-o")]
        assert len(reports) == 2 and all(flag(c, "--reference") == flag(ref[0], "-o") + "_ref.hdr.exr" for c in reports)
        # The albedo of the texture mask is not scored.
        assert not any(a.endswith("_ref.alb.exr") for c in reports for a in c)
    summary = next(
        c
        for c in (
            shlex.split(x)
            for x in make("-n", "eval", EVAL_MODEL="models/default.onnx").stdout.replace("\\\n", " ").splitlines()
            if "eval.py summary" in x
        )
    )
    public = summary[summary.index("--public") + 1 : summary.index("--flip-dir")]
    assert sorted(Path(p).name for p in public) == sorted(
        f"public-{n}{k}.images.csv" for n in names for k in ("", "-own-features")
    )


def old_cornell_box(ev, *more):
    """make eval's Cornell-box images of 1 and 2 spp (radiance and every feature), the feature
    stamp of FEATURE_SPP 16, the stand-in stages and `more`: empty files, all older than
    anything make writes."""
    images = [ev / "cornell-box" / f"cb_00000{s}spp.{k}.exr" for s in (1, 2) for k in ("hdr", *contract.FEATURES[1:])]
    (ev / "cornell-box").mkdir(parents=True)
    for p in [ev / "feature-spp-16", *map(Path, STAGES.values()), *images, *more]:
        p.touch(exist_ok=True)
        os.utime(p, (1_000_000, 1_000_000))


def test_switching_eval_model_re_denoises_even_with_an_older_model(tmp_path):
    # A real make run of one Cornell snapshot's denoised image with a stand-in denoiser: after
    # model A denoised it, EVAL_MODEL=B (a file older than the image) makes it out of date, and
    # so does going back to A (also older). Without the model stamp make kept A's image for B.
    ev, scene = tmp_path / "eval", tmp_path / "scene.lxs"
    denoise = tmp_path / "denoise.sh"
    # Writes the --model it was given into its -o file.
    denoise.write_text(
        '#!/bin/sh\nwhile [ $# -gt 0 ]; do case "$1" in --model) m="$2";; -o) o="$2";; esac; shift; done\n'
        'echo "$m" > "$o"\n'
    )
    denoise.chmod(0o755)
    a, b = tmp_path / "a.onnx", tmp_path / "b.onnx"
    old_cornell_box(ev, scene, denoise, a, b)
    target = ev / "cornell-box" / "cb_000001spp.dn.exr"

    def denoise_with(model, *flags):
        return make(
            *flags, str(target), EVAL_DIR=ev, EVAL_CB_SCENE=scene, EVAL_PROG_SPP=2, EVAL_MODEL=model, DENOISE=denoise
        )

    assert denoise_with(a).returncode == 0 and target.read_text().strip() == str(a)
    assert denoise_with(a, "-q").returncode == 0  # up to date
    assert denoise_with(b, "-q").returncode == 1  # b is older than the image, yet the image is out of date
    assert denoise_with(b).returncode == 0 and target.read_text().strip() == str(b)
    assert denoise_with(a, "-q").returncode == 1
    assert sorted(p.name for p in ev.glob("model-*")) == [f"model-{str(a).replace('/', '+')}"]


def test_changing_feature_spp_re_renders_the_features_and_not_the_radiance(tmp_path):
    # A real make run (question mode, nothing is rendered) on make eval's Cornell-box images, all
    # older than anything make writes: up to date with the FEATURE_SPP their stamp names; another
    # FEATURE_SPP makes the features out of date and leaves the radiance as it is.
    ev, scene = tmp_path / "eval", tmp_path / "scene.lxs"
    old_cornell_box(ev, scene)

    def question(kind, feature_spp):
        return make(
            "-q",
            str(ev / "cornell-box" / f"cb_000002spp.{kind}.exr"),
            EVAL_DIR=ev,
            EVAL_CB_SCENE=scene,
            EVAL_PROG_SPP=2,
            FEATURE_SPP=feature_spp,
        ).returncode

    assert question("nrm", 16) == 0 and question("hdr", 16) == 0
    assert question("nrm", 32) == 1 and question("hdr", 32) == 0
    assert sorted(p.name for p in ev.glob("feature-spp-*")) == ["feature-spp-32"]


def test_extra_noise_realizations_render_the_training_scenes_with_their_own_seeds():
    # NOISY_EXTRA_SEEDS: the training scenes' NOISY_EXTRA_LEVELS again with each seed, into
    # train/<luxest_contract.REALIZATION_DIR>/ under the scene's own name; features alike.
    cmds = dry_run("noisy", NOISY_EXTRA_SEEDS="2 3", NOISY_EXTRA_LEVELS="1 2 4")
    main = [c for c in cmds if c[0] == STAGES["TRACE"] and flag(c, "--seed") == "1"]
    extra = [c for c in cmds if c[0] == STAGES["TRACE"] and flag(c, "--seed") != "1"]
    aovs = [c for c in cmds if c[0] == STAGES["AOV_WRITE"] and flag(c, "--seed") != "1"]
    train = {flag(c, "-o").rsplit("/", 1)[1] for c in main if "/train/" in flag(c, "-o")}
    assert len(train) == 16 and len(extra) == len(aovs) == 2 * 16  # quick: 16 training scenes
    for k in ("2", "3"):
        outs = {flag(c, "-o") for c in extra if flag(c, "--seed") == k}
        d = f"data/pytest-dry-run/train/{contract.REALIZATION_DIR.format(seed=int(k))}"
        assert outs == {f"{d}/{name}" for name in train}
    assert all(flag(c, "--spp") == "4" and flag(c, "--snapshots") == "1,2,4" for c in extra)
    assert sorted(c[1:] for c in extra) == sorted([a for a in c[1:] if a not in ("--min-samples", "16")] for c in aovs)
    # None by default, in either preset; levels 1-32 when seeds are given. (The full preset's
    # dataset cut to 12 scenes: every scene has the same rules, and make reads them all.)
    for preset in ("quick", "full"):
        assert not [
            c
            for c in dry_run("noisy", PRESET=preset, DATASET_COUNT=12)
            if c[0] == STAGES["TRACE"] and flag(c, "--seed") != "1"
        ]
    full = [
        c
        for c in dry_run("noisy", PRESET="full", DATASET_COUNT=12, NOISY_EXTRA_SEEDS="2 9")
        if c[0] == STAGES["TRACE"] and flag(c, "--seed") != "1"
    ]
    assert {flag(c, "-o").split("/")[2] for c in full} == {"train"}
    assert {flag(c, "--seed") for c in full} == {"2", "9"} and {flag(c, "--snapshots") for c in full} == {
        "1,2,4,8,16,32"
    }
    # Only levels that are noisy levels, in their order.
    few = [
        c
        for c in dry_run("noisy", NOISY_EXTRA_SEEDS="2", NOISY_LEVELS="1 4 64", NOISY_EXTRA_LEVELS="4 2 1")
        if c[0] == STAGES["TRACE"] and flag(c, "--seed") == "2"
    ]
    assert few and {(flag(c, "--spp"), flag(c, "--snapshots")) for c in few} == {("4", "1,4")}
    # A seed of the noisy levels or of the references is refused.
    for bad in ("2 1", "1000001"):
        r = make("-n", "noisy", NOISY_EXTRA_SEEDS=bad)
        assert r.returncode != 0 and "NOISY_EXTRA_SEEDS" in r.stderr and len(r.stderr.strip().splitlines()) == 1, bad

    # Preprocessing and training are told the seeds and levels; no seeds when no level is rendered.
    def told(**variables):
        r = make("-n", "-W", "training/train.py", "models/pytest-dry-run.onnx", **variables)
        lines = r.stdout.replace("\\\n", " ").splitlines()
        runs = [shlex.split(line.split("&&", 1)[1]) for line in lines if "preprocess.py" in line or "train.py" in line]
        assert len(runs) == 2
        after = lambda c, f: c[
            c.index(f) + 1 : next((i for i in range(c.index(f) + 1, len(c)) if c[i].startswith("--")), len(c))
        ]
        return [(after(c, "--extra-seeds"), after(c, "--extra-spp")) for c in runs]

    assert told(NOISY_EXTRA_SEEDS="2 3") == [(["2", "3"], ["1", "2", "4", "8", "16", "32"])] * 2
    assert told(NOISY_EXTRA_SEEDS="2 3", NOISY_LEVELS="64 256 1024") == [([], [])] * 2


def test_train_py_defaults_are_the_presets_make_train_passes(monkeypatch):
    # `python train.py` without options trains as `make train` does: training/config.py's
    # defaults are read from pipelines/presets.mk (config.presets, checked against make's own
    # reading of every variable there), for the PRESET of the environment, which make reads too;
    # an environment variable replaces a preset in both.
    import sys

    sys.path.insert(0, str(ROOT / "training"))
    import config

    names = [n for n in config.presets("quick", environ={}) if n != "PRESET"]
    assert {"TRAIN_STEPS", "TRAIN_MINUTES", "TRAIN_SCHEDULE", "TRAIN_LOSS", "NOISY_LEVELS", "DATASET_DLE"} <= set(names)
    for n in names + ["PRESET"]:  # this process's environment is that of each case alone
        monkeypatch.delenv(n, raising=False)
    clean = dict(os.environ)
    for environ in (
        {"PRESET": "quick"},
        {"PRESET": "full"},
        {"PRESET": "full", "TRAIN_STEPS": "123", "DATASET_DLE": "7 8"},
    ):
        env = {**clean, **environ}
        calls = "".join(f"$(info {n}=$({n}))" for n in names)
        out = subprocess.run(
            ["make", "--no-print-directory", "-f", str(ROOT / "pipelines/presets.mk"), "-f", "-", "all"],
            input=f"{calls}\nall: ;@:\n",
            capture_output=True,
            text=True,
            check=True,
            env=env,
        ).stdout
        assert dict(line.split("=", 1) for line in out.splitlines()) == {
            n: config.presets(environ=environ)[n] for n in names
        }
        # make train's train.py command line against train.py's defaults in the same environment.
        r = subprocess.run(
            ["make", "--no-print-directory", "-n", "-W", "training/train.py", "models/pytest-dry-run.onnx"]
            + [
                f"{k}={v}"
                for k, v in {
                    **STAGES,
                    "DATASET": "pytest-dry-run",
                    "DATASET_COUNT": "12",
                    "EVAL_DIR": str(_STAGE_DIR / "eval"),
                }.items()
            ],
            cwd=ROOT,
            capture_output=True,
            text=True,
            env=env,
        )
        assert r.returncode == 0, r.stderr
        [train] = [
            shlex.split(line.split("&&", 1)[1])
            for line in r.stdout.replace("\\\n", " ").splitlines()
            if "train.py" in line
        ]
        for k, v in environ.items():
            monkeypatch.setenv(k, v)
        config._presets.cache_clear()
        try:
            made, default = config.parse(train[train.index("train.py") + 1 :]), config.parse([])
        finally:
            for k in environ:
                monkeypatch.delenv(k)
            config._presets.cache_clear()
        for key in ("noisy_spp", "dle_paths", "extra_seeds", "extra_spp", "steps", "minutes", "schedule", "loss"):
            assert getattr(made, key) == getattr(default, key), (environ, key)
    assert default.steps == 123 and default.dle_paths == [7, 8] and default.schedule == "time"
