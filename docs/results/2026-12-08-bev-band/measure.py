"""How much of the BEV raster the off-image band changed: the renderer before its fix (commit a75e661's parent, read
from git) against the fixed one, on every validation start of both benchmarks' training scenes (no trajectory tail,
as the NeuralParker BEV observation renders it), and ``before_after.png``: the first four changed Topology-Stress
images, before above after.

    python docs/results/2026-12-08-bev-band/measure.py     # from the repository root; writes measure.txt here
"""

import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

from np_sim.benchmarks import load_benchmark, validation_starts
from np_sim.bev import render_bev_batch
from np_sim.scene_arrays import pack_scenes

HERE = Path(__file__).resolve().parent
BEFORE = "a75e661~1"


def renderer_before():
    """``render_bev_batch`` as it was before the fix."""
    source = subprocess.run(["git", "show", f"{BEFORE}:np_sim/bev.py"], capture_output=True, text=True,
                            check=True).stdout
    path = Path(tempfile.mkdtemp()) / "bev_before.py"
    path.write_text(source.replace("cache=True", "cache=False"))
    spec = importlib.util.spec_from_file_location("bev_before", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["bev_before"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module.render_bev_batch


def _figure(old: np.ndarray, new: np.ndarray) -> None:
    matplotlib.use("Agg")
    fig, axes = plt.subplots(2, len(old), figsize=(2.2 * len(old), 4.6))
    for col in range(len(old)):
        for row, (images, label) in enumerate(((old, "before"), (new, "after"))):
            axes[row, col].imshow(images[col].transpose(1, 2, 0))
            axes[row, col].set_title(label, fontsize=9)
            axes[row, col].axis("off")
    fig.tight_layout()
    fig.savefig(HERE / "before_after.png", dpi=90)


def main() -> None:
    before = renderer_before()
    lines = []
    for benchmark in ("topology", "factorial"):
        arrays = pack_scenes(load_benchmark(benchmark, "train"))
        starts = validation_starts(benchmark)  # (scenes, starts per scene, 3)
        index = np.repeat(np.arange(starts.shape[0]), starts.shape[1])
        poses = starts.reshape(-1, 3)
        old, new = before(arrays, index, poses), render_bev_batch(arrays, index, poses)
        changed = (old != new).any(axis=1).reshape(len(poses), -1)  # (images, pixels): any channel differs
        per_image = changed.mean(axis=1)
        hit = per_image > 0
        if benchmark == "topology":
            _figure(old[hit][:4], new[hit][:4])
        lines.append(f"{benchmark}: {hit.sum()} of {len(poses)} images changed ({hit.mean():.0%}); in those, "
                     f"{per_image[hit].mean():.1%} of the pixels on average (most {per_image.max():.1%})")
    text = "\n".join(lines) + "\n"
    (HERE / "measure.txt").write_text(text)
    sys.stdout.write(text)


if __name__ == "__main__":
    main()
