"""The reproduction sweep: every training run the paper's simulation tables need, on Ray.

``python -m experiments.sweep --plan paper [--only TABLE ...] [--seeds 0 1 2] [--ray-address ADDR] [--out DIR]
[--shared-geometry] [--dry-run]``

Each run is a (configuration, benchmark, seed) with its own run folder under ``--out`` (default
``checkpoints/runs``); the plan and how a folder's state is decided are in `experiments.sweep_plan`. The sweep
starts a local Ray sized to this machine (or joins the cluster at ``--ray-address``; the run root must then be on
storage every node shares, with the project installed on every node) and submits one Ray task per run that is not
finished, requesting ``--cpus-per-run`` CPUs and, where the cluster has GPUs, ``--gpus-per-run`` GPUs for each
NeuralParker run (`GPU_TRAINERS`), which then trains its network with ``--device cuda`` (`np_policy.device`; a run
resumed on another device than it trained on so far continues another curve, and the trainer warns). A task runs the
configuration's trainer (``python -m np_policy.train``; ``hope_policy.train`` for the adapted HOPE) in a subprocess
(its log under ``--log-dir``): with ``--resume`` when the folder holds ``snapshot.pt``, from epoch 0 otherwise
(``--overwrite`` when a run killed before its first snapshot left files there). ``--shared-geometry`` starts new
NeuralParker runs with the trainer's ``--shared-geometry`` (the geometry branch once per scene in each update
chunk); a resumed run keeps what its rows record. Finished runs are skipped, so a killed sweep continues where it
stopped when started again; Ctrl-C first lets its trainers finish their epoch and write a snapshot
(`stop_trainers`). A trainer sent SIGTERM or SIGUSR1 (a preempting cluster, ``kill -USR1 PID``) writes its snapshot
after the epoch in progress and stops; the sweep reports it as stopped and exits with the trainer's status (128 +
the signal's number), 1 when a run failed. A run that a ``np_policy.train`` process on this machine is writing, or
whose folder holds another configuration, is left alone and reported. Progress: one bar over the runs, with each
running run's epoch read from its ``metrics.jsonl``.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from experiments.sweep_plan import TRAINERS, RunSpec, RunState, active_trainers, expand, format_table, \
    holds_run_files, load_plan, metrics_epoch, run_state
from np_sim.cli import non_negative_float, non_negative_int, positive_int
from np_sim.errors import ConfigError
from np_sim.stop_request import STOPPED_EXIT_STATUSES

RUNNABLE = ("not started", "interrupted", "started, no snapshot")
"""States the sweep trains; the others are finished, left alone, or not available yet."""
POLL_S = 2.0
"""Seconds between progress refreshes."""


GPU_TRAINERS = ("np_policy.train",)
"""Trainers that use a GPU given to their task (``--device cuda``): NeuralParker's PPO update of 8,192-sample
minibatches. The adapted HOPE's minibatches of 32 gain nothing on a GPU; its runs get none and train on the CPU."""


def run_gpus(run: RunSpec, gpus: float) -> float:
    """GPUs the Ray task of ``run`` requests: ``gpus`` for a trainer in `GPU_TRAINERS`, none otherwise."""
    return gpus if run.config.trainer in GPU_TRAINERS else 0.0


def train_argv(run: RunSpec, config_file: Path, gpus: float = 0.0, shared_geometry: bool = False) -> list[str]:
    """``np_policy.train`` arguments of ``run``, decided from its folder when the task starts (so a retried
    task resumes what an earlier attempt left): ``--resume`` when ``snapshot.pt`` exists, ``--overwrite`` when the
    folder holds run files but no snapshot (nothing to resume: a start from epoch 0 replaces them); ``--device
    cuda`` when the task holds a GPU (Ray sets ``CUDA_VISIBLE_DEVICES`` to it); ``--shared-geometry`` for a new
    ``np_policy.train`` run when ``shared_geometry`` (a resumed one keeps what it recorded)."""
    argv = ["--benchmark", run.config.benchmark, "--seed", str(run.seed), "--config", str(config_file),
            "--out", str(run.run_dir)]
    if run_gpus(run, gpus) > 0:
        argv += ["--device", "cuda"]
    if (run.run_dir / "snapshot.pt").exists():
        return [*argv, "--resume"]
    if shared_geometry and run.config.trainer == "np_policy.train":
        argv.append("--shared-geometry")
    return [*argv, "--overwrite"] if holds_run_files(run.run_dir, run.config.trainer) else argv


def _kill_with_parent() -> None:
    """In the trainer's child process: die with SIGKILL when the Ray worker that started it dies (Linux)."""
    import ctypes

    ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


def run_environment(cpus: float) -> dict[str, str]:
    """The trainer subprocess's environment: this process's, with torch's and numba's thread counts
    (``OMP_NUM_THREADS``, ``NUMBA_NUM_THREADS``) set to the run's CPUs. Ray sets only the first; numba would start
    a thread per core and raise torch's count with it (`np_policy.threads.use_threads`), so runs sharing a machine
    would each spin on every core."""
    threads = str(max(1, int(cpus)))
    return {**os.environ, "OMP_NUM_THREADS": threads, "NUMBA_NUM_THREADS": threads}


def train_run(run: RunSpec, log_path: Path, cpus: float, gpus: float = 0.0,
              shared_geometry: bool = False) -> dict[str, Any]:
    """Train (or resume) one run in a ``python -m np_policy.train`` subprocess on ``cpus`` threads (and the task's
    GPU when ``gpus``); returns its exit status and the tail of its log. This is the body of the sweep's Ray task."""
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="sweep-") as tmp:
        config_file = Path(tmp) / f"{run.name}.json"
        config_file.write_text(json.dumps(run.overrides, indent=2))
        argv = [sys.executable, "-m", run.config.trainer, *train_argv(run, config_file, gpus, shared_geometry)]
        with log_path.open("ab") as log:
            log.write(("\n$ " + " ".join(argv) + "\n").encode())
            log.flush()
            preexec = _kill_with_parent if sys.platform.startswith("linux") else None
            rc = subprocess.run(argv, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                preexec_fn=preexec, env=run_environment(cpus), check=False).returncode
    tail = log_path.read_text(errors="replace")[-2000:]
    return {"run": run.name, "rc": rc, "log": str(log_path), "tail": tail}


def _cluster_resources(args) -> tuple[float, float]:
    """(CPUs, GPUs) per run: the requested numbers, by default a whole node's CPUs (a run's torch uses every core
    it is given) and one GPU when the cluster has any."""
    import ray

    nodes = [n["Resources"] for n in ray.nodes() if n.get("Alive")]
    most_cpus = max(n.get("CPU", 0.0) for n in nodes)
    most_gpus = max(n.get("GPU", 0.0) for n in nodes)
    cpus = args.cpus_per_run or most_cpus
    gpus = args.gpus_per_run if args.gpus_per_run is not None else min(most_gpus, 1.0)
    if cpus > most_cpus or gpus > most_gpus:  # Ray would wait for such a node forever
        raise ConfigError(f"--cpus-per-run {cpus:g} / --gpus-per-run {gpus:g}: no node of the Ray cluster has that "
                          f"many (the largest has {most_cpus:g} CPUs, {most_gpus:g} GPUs)")
    return cpus, gpus


def _start_ray(address: str | None) -> None:
    import ray

    if address:
        ray.init(address=address, log_to_driver=False)
    else:
        ray.init(num_cpus=os.cpu_count(), include_dashboard=False, log_to_driver=False)


def _progress_text(running: list[RunSpec], since: float) -> str:
    """``name epoch/epochs`` of every pending run whose metrics.jsonl was written since the sweep started."""
    parts = []
    for run in running:
        path = run.run_dir / "metrics.jsonl"
        if path.exists() and path.stat().st_mtime >= since:
            parts.append(f"{run.name} {metrics_epoch(path, TRAINERS[run.config.trainer][0])}/{run.epochs}")
    return ", ".join(parts)


def run_sweep(todo: list[RunSpec], args) -> list[dict[str, Any]]:
    """Submit one Ray task per run of ``todo`` and wait for all of them, showing progress; returns the tasks'
    results."""
    import ray
    from tqdm import tqdm

    _start_ray(args.ray_address)
    try:
        cpus, gpus = _cluster_resources(args)
    except ConfigError:
        ray.shutdown()
        raise
    task = ray.remote(max_retries=1)(train_run)
    pending = {task.options(num_cpus=cpus, num_gpus=run_gpus(run, gpus)).remote(
        run, Path(args.log_dir).resolve() / f"{run.name}.log", cpus, run_gpus(run, gpus), args.shared_geometry): run
        for run in todo}
    print(f"sweep: {len(todo)} run(s) on Ray ({cpus:g} CPU, {gpus:g} GPU per run)", flush=True)
    since = time.time()
    results = []
    with tqdm(total=len(todo), unit="run", desc="sweep") as bar:
        while pending:  # a KeyboardInterrupt here ends the local Ray (atexit), whose workers' trainers die with it
            done, _ = ray.wait(list(pending), num_returns=1, timeout=POLL_S)
            for ref in done:
                run = pending.pop(ref)
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayError as exc:  # the worker died (twice: one retry), e.g. killed for memory
                    result = {"run": run.name, "rc": -1, "log": str(Path(args.log_dir) / f"{run.name}.log"),
                              "tail": f"{type(exc).__name__}: {exc}"[-2000:]}
                results.append(result)
                bar.write(f"{run.name}: {task_verdict(result)}")
                bar.update(1)
            bar.set_postfix_str(_progress_text(list(pending.values()), since), refresh=True)
    ray.shutdown()
    return results


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m experiments.sweep", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--plan", default="paper", help="'paper' (every run of the paper's simulation tables) or "
                        "a plan .json file (see experiments.sweep_plan.load_plan)")
    parser.add_argument("--only", nargs="+", metavar="TABLE", help="only the runs feeding these tables (paper: "
                        "main, staged, representation, connector, curriculum, site)")
    parser.add_argument("--seeds", nargs="+", type=non_negative_int, default=[0, 1, 2],
                        help="training seeds (default 0 1 2)")
    parser.add_argument("--ray-address", help="join this Ray cluster (default: start a local Ray on this machine)")
    parser.add_argument("--out", type=Path, default=Path("checkpoints/runs"), help="run root (default "
                        "checkpoints/runs)")
    parser.add_argument("--log-dir", type=Path, default=Path("results/sweep/logs"),
                        help="training logs, one per run (default results/sweep/logs)")
    parser.add_argument("--cpus-per-run", type=positive_int, help="CPUs per run (default: a whole node's)")
    parser.add_argument("--gpus-per-run", type=non_negative_float,
                        help="GPUs per run (default: 1 when the cluster has GPUs)")
    parser.add_argument("--shared-geometry", action="store_true", help="start new NeuralParker runs with "
                        "np_policy.train --shared-geometry (about 1.5x faster updates on Factorial; another float "
                        "summation order, so another curve); resumed runs keep what they recorded")
    parser.add_argument("--dry-run", action="store_true", help="list the runs, their state and the estimated "
                        "compute left; train nothing")
    return parser


def _check_args(args) -> None:
    if args.out.exists() and not args.out.is_dir():
        raise ConfigError(f"--out: {args.out} is a file, expected a folder of run folders")


def main(argv=None) -> int:
    """CLI entry point; returns the exit status (0: every run finished or left alone as reported)."""
    args = _parser().parse_args(argv)
    try:
        _check_args(args)
        plan, config_dir = load_plan(args.plan)
        runs = expand(plan, args.seeds, args.out, args.only, config_dir)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    active = active_trainers()
    states = [run_state(run, active) for run in runs]
    print(format_table(runs, states), flush=True)
    if args.dry_run:
        return 0
    todo = [run for run, state in zip(runs, states) if state.kind in RUNNABLE]
    _report_skipped(runs, states)
    if not todo:
        print("sweep: nothing to train")
        return 0
    try:
        results = run_sweep(todo, args)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        stop_trainers(todo)
        print("sweep: interrupted; its trainers are stopped. Run the same command again to continue: finished runs "
              "are skipped, interrupted ones resume from their snapshot.", file=sys.stderr)
        return 130
    failed = [r for r in results if r["rc"] != 0 and r["rc"] not in STOPPED_EXIT_STATUSES]
    stopped = [r for r in results if r["rc"] in STOPPED_EXIT_STATUSES]
    for result in failed:
        print(f"{result['run']}: training failed (exit {result['rc']}); end of {result['log']}:\n{result['tail']}",
              file=sys.stderr)
    for result in stopped:
        print(f"{result['run']}: {task_verdict(result)}", file=sys.stderr)
    return 1 if failed else stopped[0]["rc"] if stopped else 0


def task_verdict(result: dict[str, Any]) -> str:
    """What a finished task's exit status says of its run: done, stopped on request at a snapshot
    (`np_sim.stop_request`: the next sweep resumes it), or failed."""
    rc = result["rc"]
    if rc == 0:
        return "done"
    if rc in STOPPED_EXIT_STATUSES:
        return (f"stopped by {signal.Signals(rc - 128).name} at a snapshot; the same sweep command resumes it "
                f"(log {result['log']})")
    return f"FAILED (exit {rc}, log {result['log']})"


def stop_trainers(runs: list[RunSpec]) -> list[int]:
    """Ask the trainers of ``runs`` running on this machine to stop after the epoch (update) in progress, each with
    a snapshot (SIGUSR1, `np_sim.stop_request`), and wait until they have; another Ctrl-C stops the wait, and the
    trainers then die with the sweep's Ray. Returns the process ids asked. Called when the sweep is interrupted:
    without it the epochs since each run's last periodic snapshot would be lost."""
    ours = {run.run_dir.resolve() for run in runs}
    pids = [pid for out, pid in active_trainers().items() if out in ours]
    for pid in pids:
        try:
            os.kill(pid, signal.SIGUSR1)
        except ProcessLookupError:  # it ended meanwhile
            pass
    if pids:
        print(f"sweep: stopping {len(pids)} trainer(s) after the epoch in progress, each writing its snapshot; "
              "Ctrl-C again to kill them now", file=sys.stderr, flush=True)
    try:
        while set(pids) & set(active_trainers().values()):  # an ended trainer (a zombie too) has no command line
            time.sleep(0.5)
    except KeyboardInterrupt:
        pass
    return pids


def _report_skipped(runs: list[RunSpec], states: list[RunState]) -> None:
    """One line per run the sweep does not train and that is not finished."""
    for run, state in zip(runs, states):
        if state.kind not in RUNNABLE and state.kind != "finished":
            print(f"sweep: skipping {run.name}: {state.kind}" + (f" ({state.detail})" if state.detail else ""))


if __name__ == "__main__":
    sys.exit(main())
