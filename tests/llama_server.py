"""A ``llama-server`` binary for the tests that plan through llama.cpp's own server.

The one ``SMARTLLM_LLAMA_SERVER`` names, else one built once per cache folder from the llama.cpp inside the
installed llama-cpp-python's source distribution (its ``vendor/llama.cpp``, with ``tools/server``): the same
source and build settings as the in-process backend's, so that both compute the same logits. The build
takes about four minutes on two cores and needs the source distribution from PyPI (or pip's cache).
"""

from __future__ import annotations

import fcntl
import importlib.metadata
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path


def llama_server() -> Path:
    named = os.environ.get("SMARTLLM_LLAMA_SERVER")
    if named:
        return Path(named)
    version = importlib.metadata.version("llama-cpp-python")
    home = Path(os.environ["SMARTLLM_CACHE_DIR"]).resolve() / "llama-server"
    binary = home / f"llama-server-{version}"
    home.mkdir(parents=True, exist_ok=True)
    with open(home / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one build, whichever test process asks first
        if not binary.exists():
            _build(version, binary)
    return binary


def _build(version: str, binary: Path) -> None:
    tools = Path(sys.executable).parent  # cmake and ninja, from the test extra
    with tempfile.TemporaryDirectory(dir=binary.parent) as work:
        _run([sys.executable, "-m", "pip", "download", f"llama-cpp-python=={version}", "--no-binary",
              "llama-cpp-python", "--no-deps", "--quiet", "-d", work], work)
        (archive,) = Path(work).glob("llama_cpp_python-*.tar.gz")
        with tarfile.open(archive) as sdist:
            root = f"llama_cpp_python-{version}/vendor/llama.cpp/"
            sdist.extractall(work, members=[m for m in sdist.getmembers() if m.name.startswith(root)],
                             filter="data")
        source, build = Path(work) / root, Path(work) / "build"
        _run([str(tools / "cmake"), "-S", str(source), "-B", str(build), "-G", "Ninja",
              f"-DCMAKE_MAKE_PROGRAM={tools / 'ninja'}", "-DCMAKE_BUILD_TYPE=Release", "-DBUILD_SHARED_LIBS=OFF",
              "-DLLAMA_BUILD_TESTS=OFF", "-DLLAMA_BUILD_EXAMPLES=OFF", "-DLLAMA_BUILD_SERVER=ON",
              "-DLLAMA_USE_PREBUILT_UI=OFF", "-DLLAMA_OPENSSL=OFF", "-DLLAMA_CURL=OFF"], work)
        _run([str(tools / "cmake"), "--build", str(build), "--target", "llama-server",
              "-j", str(os.cpu_count() or 1)], work)
        shutil.move(build / "bin" / "llama-server", binary)


def _run(command: list[str], work: str) -> None:
    done = subprocess.run(command, capture_output=True, text=True, cwd=work)
    if done.returncode != 0:
        raise RuntimeError(f"building llama-server: {' '.join(command[:4])} ... failed "
                           f"(set SMARTLLM_LLAMA_SERVER to a llama-server binary instead):\n"
                           f"{(done.stdout + done.stderr)[-3000:]}")
