"""Where a NeuralParker training run's network trains: the CPU (the default) or a CUDA GPU.

Only the actor–critic, its optimiser and the PPO update move to the device; the envs, the start samplers, the
frozen BEV encoder and every random choice outside the policy's action sampling stay on the CPU. The network is
initialised on the CPU and then moved, so a run starts from the same weights on any device. What differs on a GPU:
the action samples come from the GPU's generator (seeded by the same ``torch.manual_seed``, but another stream)
and its kernels round differently, so a GPU run is a different curve of the same recipe; it is repeatable on the
same GPU and library versions only as far as CUDA's kernels are (PyTorch's "Reproducibility" notes). On the CPU a
resumed run repeats an uninterrupted one bit for bit.
"""

from __future__ import annotations

from typing import Any

import torch

from np_sim.errors import ConfigError

DEVICE_CHOICES = "cpu, cuda, cuda:N or auto"


def training_device(text: str) -> torch.device:
    """``text`` as the device to train on: ``cpu``, ``cuda``, ``cuda:N``, or ``auto`` (the first CUDA GPU when torch
    sees one, else the CPU). ConfigError naming ``--device`` for anything else or a GPU this process cannot see."""
    if text == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    try:
        device = torch.device(text)
    except (RuntimeError, TypeError) as exc:
        raise ConfigError(f"--device: expected {DEVICE_CHOICES}, got {text!r}") from exc
    if device.type == "cpu":
        return torch.device("cpu")
    if device.type != "cuda":
        raise ConfigError(f"--device: expected {DEVICE_CHOICES}, got {text!r} (training runs on the CPU or a CUDA "
                          "GPU)")
    visible = torch.cuda.device_count() if torch.cuda.is_available() else 0
    if visible == 0:
        raise ConfigError(f"--device {text}: this torch sees no CUDA GPU (torch.cuda.is_available() is False; "
                          f"torch {torch.__version__} built for CUDA {torch.version.cuda}); use --device cpu")
    if device.index is not None and device.index >= visible:
        raise ConfigError(f"--device {text}: this process sees {visible} CUDA GPU(s), numbered 0 to {visible - 1}")
    return device


def device_label(device: torch.device) -> str:
    """What a metrics row and the provenance record say the run trained on: ``cpu`` or ``cuda:N (GPU name)``."""
    if device.type != "cuda":
        return "cpu"
    index = torch.cuda.current_device() if device.index is None else device.index
    return f"cuda:{index} ({torch.cuda.get_device_name(index)})"


def sampling_rng_state(device: torch.device) -> dict[str, Any]:
    """The generator states a snapshot needs to continue the policy's action sampling on ``device``: the CPU's
    always, the GPU's too when training on one."""
    state = {"torch_rng": torch.get_rng_state()}
    if device.type == "cuda":
        state["cuda_rng"] = torch.cuda.get_rng_state(device)
    return state


def restore_sampling_rng(payload: dict[str, Any], device: torch.device) -> None:
    """Inverse of `sampling_rng_state`; a snapshot taken on the CPU resumed on a GPU keeps the GPU's seeded
    stream (the curve then differs from an uninterrupted run's, as ``_resume`` warns)."""
    torch.set_rng_state(payload["torch_rng"])
    if device.type == "cuda" and "cuda_rng" in payload:
        torch.cuda.set_rng_state(payload["cuda_rng"], device)
