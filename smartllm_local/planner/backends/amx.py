"""Whether llama.cpp's AMX kernels run on this machine, and loading a model without them where they do not.

A llama.cpp built where the processor reports AMX (Intel's matrix tiles) multiplies quantized weights on AMX
tiles, which llama.cpp keeps in an "extra" buffer type of its own. Some virtual machines report AMX and grant
its permission, yet trap its instructions: the process dies at its first prompt, with no message, of SIGILL
(measured on a 2-core Xeon guest, 2026-11-28: ``tilezero`` in ``ggml_backend_amx_mul_mat``) or of SIGSEGV (a
general protection fault in ``libggml-cpu``, another 2-core guest, 2026-12-01). So where the build has AMX, a
child process loads the model and evaluates a few tokens first; where that child dies of a signal and a second,
loading the model without llama.cpp's extra buffer types (its weights in plain CPU buffers, computed with
AVX-512 or AVX2), ends well, the model is loaded that way. The answer is kept in the cache per llama.cpp build,
machine, model file and probe.
"""

from __future__ import annotations

import contextlib
import hashlib
import platform
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from ...files import read_cache_map, remember_in_cache_map

#: What the child runs: load the model (argv[1]; its weights in plain buffers where argv[2] is "plain") and evaluate
#: a few tokens, as the planner's first prompt does.
PROBE = """\
import sys
import llama_cpp
from smartllm_local.planner.backends.amx import without_extra_buffers
with without_extra_buffers(llama_cpp, wanted=sys.argv[2:] == ["plain"]):
    llm = llama_cpp.Llama(model_path=sys.argv[1], n_ctx=64, n_batch=32, n_threads=1, verbose=False)
llm.eval(llm.tokenize(b"def probe(): return 1"))
"""
PROBE_TIMEOUT = 120.0  # seconds: a load from a cold disk; past it the answer is unknown and not kept
CACHE_FILE = "amx.json"


def amx_in_build(llama_cpp: Any) -> bool:
    """Whether this llama.cpp was built with AMX kernels (its system information says ``AMX_INT8 = 1``)."""
    return "AMX_INT8 = 1" in llama_cpp.llama_print_system_info().decode("utf-8", errors="replace")


def probe(model_path: str | Path, plain: bool = False, code: str = PROBE) -> int | None:
    """Run ``code`` in a child Python with the model's path (and "plain" where ``plain``); its exit status
    (negative: the signal that ended it), or None where it did not end within :data:`PROBE_TIMEOUT` (the child
    is killed, not left behind)."""
    try:
        command = [sys.executable, "-c", code, str(model_path), *(["plain"] if plain else [])]
        return subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, timeout=PROBE_TIMEOUT, check=False).returncode
    except subprocess.TimeoutExpired:
        return None


def amx_runs(llama_cpp: Any, model_path: str | Path, cache_dir: Path | None = None,
             run_probe: Callable[[str | Path, bool], int | None] = probe) -> bool:
    """Whether the model may be loaded with llama.cpp's extra buffer types: yes where the build has no AMX,
    else as the probes found (kept in ``cache_dir``): no where the child with them died of a signal and the
    child without them ended well; a child that died without them too has another fault, which the load then
    reports; where a child did not end, yes, not kept."""
    if not amx_in_build(llama_cpp) or not Path(model_path).is_file():
        return True  # (a missing file: the load says so, no child need try it first)
    if cache_dir is None:
        from ...world.scenes import cache_root
        cache_dir = cache_root()
    path = cache_dir / CACHE_FILE
    key = _machine_key(llama_cpp, Path(model_path))
    known = read_cache_map(path)
    if key in known:
        return bool(known[key])
    traps = _traps(model_path, run_probe)
    if traps is None:
        return True
    runs = not traps
    remember_in_cache_map(path, key, runs)  # where it cannot be written: a probe per process, nothing else
    return runs


def _traps(model_path: str | Path, run_probe: Callable[[str | Path, bool], int | None]) -> bool | None:
    """Whether the model dies with llama.cpp's extra buffer types and runs without them; None where a child
    did not end."""
    status = run_probe(model_path, False)
    if status is None:
        return None
    if status >= 0:
        return False
    plain = run_probe(model_path, True)
    return None if plain is None else plain == 0


@contextlib.contextmanager
def without_extra_buffers(llama_cpp: Any, wanted: bool) -> Iterator[None]:
    """Where ``wanted``, models loaded inside take no extra buffer types (no AMX, no repacked weights):
    llama-cpp-python 0.3.36 cannot ask for that, and reads the model's parameters from llama.cpp's defaults,
    which this wraps while the model loads."""
    if not wanted:
        yield
        return
    module = llama_cpp.llama_cpp
    defaults = module.llama_model_default_params

    def plain() -> Any:
        params = defaults()
        params.use_extra_bufts = False
        return params

    module.llama_model_default_params = plain
    try:
        yield
    finally:
        module.llama_model_default_params = defaults


def _machine_key(llama_cpp: Any, model_path: Path) -> str:
    """The build, the processor (its name and flags), the kernel, the model file (name and size) and the probe
    (an answer another probe gave is asked again)."""
    cpu = ""
    with contextlib.suppress(OSError):
        lines = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace").splitlines()
        cpu = "\n".join(dict.fromkeys(x for x in lines if x.startswith(("model name", "flags"))))
    try:
        size = model_path.stat().st_size
    except OSError:
        size = -1
    parts = [getattr(llama_cpp, "__version__", ""), platform.machine(), platform.release(), cpu,
             model_path.name, str(size), PROBE]
    return hashlib.sha256("\0".join(parts).encode("utf-8")).hexdigest()[:24]
