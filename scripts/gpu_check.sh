#!/usr/bin/env bash
# The planner on an NVIDIA GPU, on a machine with no package registry (the device tool's lent machines).
#
#   scripts/gpu_check.sh pack          here, with pip's registry: llama-cpp-python's source, trimmed to what a
#                                      CUDA build needs, and py3.12 wheels of what such a machine lacks, in build/gpu/
#   scripts/gpu_check.sh run           there (build/gpu carried): build llama-cpp-python with CUDA (about 3.5 min
#                                      on 16 cores), write random-weight Llama-2-7B and -70B shapes
#                                      (scripts/random_gguf.py), plan kitchen-01 on each with every layer on the
#                                      GPU, and print one table
#   scripts/gpu_check.sh run --cpu     the same on this machine's CPU with a tiny shape and the installed
#                                      llama-cpp-python: how the script itself is tested where no GPU is lent
#
# Each run also plans in a process that imports numpy before llama_cpp (the order that crashed a CUDA build).
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
GPU=$ROOT/build/gpu
PY=${PYTHON:-python3}
LLAMA_CPP_PYTHON=0.3.36

pack() {
    mkdir -p "$GPU/wheels"
    local tmp
    tmp=$(mktemp -d)
    "$PY" -m pip download --quiet --no-deps --no-binary :all: "llama-cpp-python==$LLAMA_CPP_PYTHON" -d "$tmp"
    tar -xzf "$tmp"/llama_cpp_python-*.tar.gz -C "$tmp"
    local src=$tmp/llama_cpp_python-$LLAMA_CPP_PYTHON vendor
    vendor=$src/vendor/llama.cpp
    # What a CUDA build reads: the CPU and CUDA backends, the library, the chat-template code.
    find "$vendor/models" -type f ! -name 'ggml-vocab-llama-spm.gguf' -delete
    rm -rf "$vendor"/{docs,benches,tests,examples,media,.git,.github} "$src"/{.git,.github}
    find "$vendor/tools" -mindepth 1 -maxdepth 1 ! -name mtmd -exec rm -rf {} +
    find "$vendor/ggml/src" -mindepth 1 -maxdepth 1 -type d -name 'ggml-*' ! -name ggml-cpu ! -name ggml-cuda \
        -exec rm -rf {} +
    tar -czf "$GPU/llama-cpp-python-src.tar.gz" -C "$tmp" "llama_cpp_python-$LLAMA_CPP_PYTHON"
    # Python 3.12 wheels of what the build and the project import and such a machine lacks (numpy, typer, rich,
    # jinja2, matplotlib and msgpack it has), each without its own needs: all of them are listed.
    "$PY" -m pip download --quiet --no-deps --only-binary :all: --python-version 3.12 \
        --platform manylinux2014_x86_64 --platform manylinux_2_17_x86_64 --platform any -d "$GPU/wheels" \
        scikit-build-core pathspec diskcache gguf pyyaml tqdm ai2thor==5.0.0 procthor==0.0.1.dev2 botocore \
        aws-requests-auth blinker flask itsdangerous jmespath jsonschema jsonschema-specifications referencing \
        rpds-py progressbar2 python-utils python-xlib urllib3 python-dateutil werkzeug
    rm -rf "$tmp"
    du -sh "$GPU"
}

build() {
    local site=$1 tmp
    tmp=$(mktemp -d)
    tar -xzf "$GPU/llama-cpp-python-src.tar.gz" -C "$tmp"
    "$PY" -m pip install --quiet --no-deps --no-index --target "$site" "$GPU"/wheels/*.whl
    PYTHONPATH=$site CMAKE_BUILD_PARALLEL_LEVEL=$(nproc) \
        CMAKE_ARGS="-DGGML_CUDA=on -DCMAKE_CUDA_ARCHITECTURES=native -DGGML_CUDA_FA=OFF -DLLAVA_BUILD=OFF" \
        "$PY" -m pip install --quiet --no-build-isolation --no-deps --no-index --target "$site" \
        "$tmp/llama_cpp_python-$LLAMA_CPP_PYTHON"
    rm -rf "$tmp"
}

run() {
    local cpu=0 layers=-1 shapes=(7b 70b) work site
    [[ ${1:-} == --cpu ]] && { cpu=1; layers=0; shapes=(tiny); }
    work=${OUT:-$(mktemp -d)}
    site=$GPU/site
    if [[ $cpu == 0 ]]; then
        nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader
        local began=$SECONDS
        build "$site"
        echo "built llama-cpp-python with CUDA in $((SECONDS - began)) s"
        export PYTHONPATH=$site:$ROOT
    else
        export PYTHONPATH=$ROOT
    fi
    for shape in "${shapes[@]}"; do
        local model=${GGUF_DIR:-/tmp}/random-llama-2-$shape.gguf
        [[ -f $model ]] || "$PY" "$ROOT/scripts/random_gguf.py" --shape "$shape" --out "$model" >/dev/null
        local began=$SECONDS
        "$PY" -X faulthandler -m smartllm_local plan --task kitchen-01 --model "$model" --n-ctx 4096 \
            --n-gpu-layers "$layers" --prefix-cache off --out "$work/$shape" >"$work/$shape.log" 2>&1 \
            || { echo "plan on the $shape shape failed:"; tail -20 "$work/$shape.log"; exit 1; }
        echo "$((SECONDS - began))" >"$work/$shape.wall"
        "$PY" -X faulthandler -c "import numpy, sys; assert 'llama_cpp' not in sys.modules
from smartllm_local.planner.backends import load_backend
load_backend('llamacpp', '$model', n_ctx=512, n_gpu_layers=$layers, prefix_cache='off').close()" \
            || { echo "numpy imported first: loading the $shape shape failed"; exit 1; }
    done
    "$PY" - "$work" "${shapes[@]}" <<'EOF'
import json, sys
from pathlib import Path
work = Path(sys.argv[1])
print("| shape | plan wall s | decomposition s (prompt s, prompt tokens) | coalition s (prompt s) | allocation s (prompt s) |")
print("|---|---:|---:|---:|---:|")
for shape in sys.argv[2:]:
    cells = []
    for stage in ("decomposition", "coalition", "allocation"):
        if not (work / shape / stage / "timings.json").is_file():
            cells.append("- (refused before)")  # a random model may write the refusal line
            continue
        t = json.loads((work / shape / stage / "timings.json").read_text())
        extra = f", {t['prompt_tokens']:,}" if stage == "decomposition" else ""
        cells.append(f"{t['seconds']:.1f} ({t['prompt_seconds']:.1f}{extra})")
    print(f"| {shape} | {(work / f'{shape}.wall').read_text().strip()} | " + " | ".join(cells) + " |")
EOF
}

case ${1:-} in
    pack) pack ;;
    run) shift; run "$@" ;;
    *) echo "usage: $0 pack | run [--cpu]" >&2; exit 2 ;;
esac
