"""What the training tests share, built once per session: a tiny preprocessed dataset and the
denoiser runs the tests export to ONNX, with their exports.

Exporting a kernel-predicting model takes tens of seconds on two cores (torch.onnx traces some
600 nodes with dynamic shapes; a direct-head model a few seconds), and the tests need one export
of each network shape they check. So each is exported once, in two worker processes started as
soon as the tests are collected, while the other tests run: the models the selected tests name
(`@pytest.mark.models(...)`, or the parity test's parameter). A test that needs one waits for it
(`models[name]`). The models are read only: a test that trains or exports writes into its own
tmp_path."""

import concurrent.futures
import contextlib
import functools
import multiprocessing
import shutil
import sys
import tempfile
import threading
from pathlib import Path

import numpy as np
import pytest

TRAINING = Path(__file__).resolve().parent.parent
if str(TRAINING) not in sys.path:
    sys.path.insert(0, str(TRAINING))

WIDTH = 8
"""U-Net width of every test network (plumbing, not quality)."""


def tiny_split(d, side, rng):
    """A rendered split of one scene `g` in directory `d` (created): a 64-spp reference (seed 2)
    and a 4-spp level (seed 1) with every feature, side x side random pixels drawn from `rng`."""
    import luxest_contract as contract

    d.mkdir(parents=True)
    contract.write(
        d / contract.image_name("g", "hdr"), rng.random((side, side, 3)), {contract.SAMPLES: 64, contract.SEED: 2}
    )
    for kind in contract.FEATURES:
        contract.write(
            d / contract.image_name("g", kind, 4), rng.random((side, side, 3)), {contract.SAMPLES: 4, contract.SEED: 1}
        )
    return d


def make_tiny_prep(root):
    """tiny_split's scene preprocessed at 4 spp without local-estimate images into root/prep, and
    train.py's arguments for it: 32² crops, batches of 2, one thread."""
    import preprocess

    d = tiny_split(root / "data" / "train", 32, np.random.default_rng(4))
    preprocess.preprocess_split(d, root / "prep" / "train", [4], [])
    return ["--prep-dir", str(root / "prep"), *"--noisy-spp 4 --dle-paths --crop 32 --batch 2 --threads 1".split()]


# --- The models (built in worker processes) ---------------------------------------------------


def _random_run(run_dir, seed, **network):
    """A run directory of a randomly initialised network (width WIDTH, `network`: config.Config
    fields) that no training touched."""
    import config
    import export
    import model
    import torch

    torch.manual_seed(seed)
    cfg = config.Config(base_width=WIDTH, **network)
    export.write_run(run_dir, cfg, model.denoiser(cfg).state_dict())
    return run_dir


def _export(run_dir, onnx, **options):
    import export

    export.export(run_dir, onnx, **options)
    return {"run": run_dir, "onnx": onnx}


def build_model(name, root, prep_args, done):
    """Builds model `name` under `root` in a worker process, its progress messages in
    `root/<name>.log`; `done`: {name: result} of the models it starts from. Returns {"run": run
    directory, "onnx": its export}."""
    with open(Path(root) / f"{name}.log", "w") as log, contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
        return _build_model(name, Path(root), prep_args, done)


def _build_model(name, root, prep_args, done):
    import torch

    torch.set_num_threads(1)
    if name == "kpn":  # hdr, alb, nrm; no detail gates
        return _export(
            _random_run(root / name, 2, features=["hdr", "alb", "nrm"], detail_gate=False), root / f"{name}.onnx"
        )
    if name == "direct":
        run = _random_run(root / name, 2, head="direct", features=["hdr", "alb", "nrm"], detail_gate=False)
        return _export(run, root / f"{name}.onnx")
    if name == "emi":  # + the emission; no detail gates
        run = _random_run(root / name, 2, features=["hdr", "alb", "nrm", "emi"], detail_gate=False)
        return _export(run, root / f"{name}.onnx")
    if name == "ema":  # the emi run exported adding back the antialiased emission: all five features
        return _export(done["emi"]["run"], root / f"{name}.onnx", antialiased_emission=True)
    if name == "gated":  # all five features, detail gates: trained 3 steps on the tiny dataset
        import train

        train.main(
            prep_args + ["--run-dir", str(root / name), "--base-width", str(WIDTH), "--detail-gate", "--steps", "3"]
        )
        return _export(root / name, root / f"{name}.onnx")
    if name == "five":  # gated grown to 5 scales (train.py --init-from), its new 1/16 head given random weights
        import config
        import export
        import train

        grown = ["--run-dir", str(root / "five-grown"), "--base-width", str(WIDTH), "--detail-gate", "--scales", "5"]
        train.main(prep_args + grown + ["--minutes", "0", "--init-from", str(done["gated"]["onnx"])])
        state = torch.load(root / "five-grown" / "checkpoint.pt", weights_only=False)["model"]
        torch.manual_seed(5)
        state["heads.4.weight"] = torch.randn_like(state["heads.4.weight"])  # its bias stays zero
        export.write_run(root / name, config.Config.load(root / "five-grown" / "config.json"), state)
        return _export(root / name, root / f"{name}.onnx")
    raise ValueError(f"no test model {name!r}")


# name: the models it starts from; in the order the workers take them: the soup tests' first
# (they run before the training tests), then the longest chain.
MODELS = {"direct": (), "gated": (), "five": ("gated",), "emi": (), "ema": ("emi",), "kpn": ()}
WORKERS = 2


class Models:
    """The shared models `wanted` (and those they start from), built in the background:
    `models[name]` waits for model `name` and returns {"run": Path, "onnx": Path}."""

    def __init__(self, wanted):
        self.root = Path(tempfile.mkdtemp(prefix="luxest-test-models-"))
        self.prep_args = make_tiny_prep(self.root / "tiny")
        while any(d not in wanted for n in wanted for d in MODELS[n]):
            wanted = wanted | {d for n in wanted for d in MODELS[n]}
        self.futures = {name: concurrent.futures.Future() for name in MODELS if name in wanted}
        self.started, self.running, self.closed, self.lock = set(), 0, False, threading.RLock()
        self.pool = None
        if self.futures:
            self.pool = concurrent.futures.ProcessPoolExecutor(WORKERS, mp_context=multiprocessing.get_context("spawn"))
            self._next()

    def _next(self):
        """Gives the free workers the first models in MODELS' order whose sources are built."""
        with self.lock:
            while self.running < WORKERS and not self.closed:
                ready = [
                    n for n in self.futures if n not in self.started and all(self.futures[d].done() for d in MODELS[n])
                ]
                if not ready:
                    return
                name = ready[0]
                self.started.add(name)
                failed = next((self.futures[d].exception() for d in MODELS[name] if self.futures[d].exception()), None)
                if failed is not None:
                    self.futures[name].set_exception(failed)
                    continue
                self.running += 1
                done = {d: self.futures[d].result() for d in MODELS[name]}
                job = self.pool.submit(build_model, name, str(self.root), self.prep_args, done)
                job.add_done_callback(functools.partial(self._finished, name))

    def _finished(self, name, job):
        with self.lock:
            self.running -= 1
        if job.cancelled():
            self.futures[name].cancel()
        elif job.exception() is not None:
            self.futures[name].set_exception(job.exception())
        else:
            self.futures[name].set_result(job.result())
        self._next()

    def __getitem__(self, name):
        if name not in self.futures:
            raise KeyError(f"test model {name!r} is not built: name it in the test's @pytest.mark.models(...)")
        return self.futures[name].result()

    def close(self):
        """Ends the workers (a model still being built is one no test asks for any more)."""
        with self.lock:
            self.closed = True
        if self.pool is not None:
            processes = list((self.pool._processes or {}).values())
            self.pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                process.terminate()
                process.join()
        shutil.rmtree(self.root, ignore_errors=True)


def pytest_configure(config):
    config.addinivalue_line("markers", "models(*names): the shared models (conftest.MODELS) the test asks `models` for")


def wanted_models(item):
    """The shared models a collected test needs: those of its `models` marker, the `name` it is
    parametrized with, or every one (a test that asks for `models` without saying which)."""
    if "models" not in getattr(item, "fixturenames", ()):
        return set()
    marker = item.get_closest_marker("models")
    if marker is not None:
        return set(marker.args)
    params = getattr(getattr(item, "callspec", None), "params", {})
    return {params["name"]} if params.get("name") in MODELS else set(MODELS)


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(session, config, items):
    # Start building the models as soon as the selected tests are known.
    if any("models" in getattr(item, "fixturenames", ()) for item in items):
        config.luxest_models = Models(set().union(*(wanted_models(item) for item in items)))


def pytest_unconfigure(config):
    models = getattr(config, "luxest_models", None)
    if models is not None:
        models.close()


@pytest.fixture(scope="session")
def models(request):
    return request.config.luxest_models


@pytest.fixture(scope="session")
def tiny_prep(models):
    """train.py's arguments for the shared tiny preprocessed dataset (read only)."""
    return list(models.prep_args)
