"""smartllm-local: SMART-LLM's multi-robot task planning on local models, executed in AI2-THOR."""

import contextlib
import ctypes
import sys

# One C++ runtime for llama.cpp's libraries, whatever was loaded before them: a CUDA build's libggml-cuda carries
# C++ stream code of its own, and where numpy (a C++ extension) had set the C++ runtime up first, llama.cpp's
# model load called into that copy and crashed (docs/servers-and-gpus.md). The system's runtime, made global
# before llama.cpp loads (lazily, by the backends), is then the one every library binds to.
if sys.platform.startswith("linux"):
    with contextlib.suppress(OSError):
        ctypes.CDLL("libstdc++.so.6", mode=ctypes.RTLD_GLOBAL)

__version__ = "0.1.0"
