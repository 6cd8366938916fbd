"""Sharing the cores with other programs.

llama.cpp as ``pip install llama-cpp-python`` builds it runs its threads through OpenMP (GNU libgomp), and
torch's CPU kernels do too. By default a libgomp thread that waits at a barrier spins 300,000 times before it
sleeps, and llama.cpp passes hundreds of barriers per token. Alone on its cores that costs nothing; beside
another busy process with a thread per core, each spinning thread holds a core the other process needs, and
both crawl. Measured on 2 cores with Qwen2.5-Coder-0.5B (docs/measurements.md, "Sharing the cores"), a
``plan`` alone and two at once: spinning 300,000 times, 13 s and 90 s; 1,000 times, 14 s and 26 s; never
(a passive wait), 17 s and 19 s. A short spin keeps nearly all the speed alone and shares the cores.

libgomp reads its settings once, when it is loaded, so they are set before llama.cpp or torch is imported.
A user's own ``OMP_WAIT_POLICY`` or ``GOMP_SPINCOUNT`` is kept.
"""

from __future__ import annotations

import os

WAIT_SETTINGS = ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")
SPINS = "1000"  # how long a waiting OpenMP thread spins before it sleeps (libgomp's own default: 300,000)


def share_cores(environ: dict[str, str] | None = None) -> bool:
    """Make OpenMP threads that wait spin briefly, then sleep, unless the user chose a wait setting; whether it
    set one. Call before llama.cpp or torch is loaded (later, libgomp has read its settings already)."""
    env = os.environ if environ is None else environ
    if any(name in env for name in WAIT_SETTINGS):
        return False
    env["GOMP_SPINCOUNT"] = SPINS
    return True
