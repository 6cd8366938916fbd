#!/usr/bin/env bash
# The planner on an NVIDIA GPU, on a machine with no package registry (the device tool's lent machines).
#
#   scripts/gpu_check.sh pack          here, with pip's registry: llama-cpp-python's source, trimmed to what a
#                                      CUDA build needs, and py3.12 wheels of what such a machine lacks, in build/gpu/
#   scripts/gpu_check.sh run           there (build/gpu carried): build llama-cpp-python with CUDA (about 3.5 min
#                                      on 16 cores) while random-weight Llama-2-7B and -70B shapes are written
#                                      (scripts/random_gguf.py); then, on each shape with every layer on the GPU,
#                                      plan kitchen-01 and run `bench` (the prompt path against llama.cpp alone,
#                                      decoding, prefix reuse); on the first shape, run the whole household
#                                      benchmark with K tasks planned at once (`benchmark run --parallel K`, K in
#                                      GPU_CHECK_PARALLEL, default "47 16 4 1"); print the tables (scripts/gpu_table.py)
#   scripts/gpu_check.sh run --cpu     the same on this machine's CPU with a tiny shape, two tasks and K 1 and 2, and
#                                      the installed llama-cpp-python: how the script itself is tested where no GPU is
#                                      lent
#
# Each run first loads a model in processes that import numpy before llama_cpp (the order that crashed a CUDA
# build), in variants that tell its causes apart, with a native backtrace (cuda-gdb) where one crashes.
# GPU_CHECK_SHAPES (default "7b"; "7b 70b" adds the 70B shape) names the shapes, in order; GPU_CHECK_SECONDS
# (default 560) bounds the run: a shape's bench, or a K's benchmark run, is left out when it would not fit, and a
# run that would pass it is cut, counting the tasks it scored. The largest K comes first: on an H200 the CUDA
# build takes 200 s and the benchmark one task at a time about 240 s (2026-11-27), so one call of the device tool
# (at most 600 s) holds the build and a few K. GPU_CHECK_TASKS (default: every task; with --cpu
# "kitchen-01 kitchen-02") names the tasks of the benchmark runs.
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
    # Python 3.12 wheels of what the build and the project import and such a machine lacks (numpy, scipy, typer,
    # rich, jinja2, matplotlib, msgpack, networkx and pyparsing it has), each without its own needs: all are listed.
    "$PY" -m pip download --quiet --no-deps --only-binary :all: --python-version 3.12 \
        --platform manylinux2014_x86_64 --platform manylinux_2_17_x86_64 --platform any -d "$GPU/wheels" \
        scikit-build-core pathspec diskcache gguf pyyaml tqdm ai2thor==5.0.0 procthor==0.0.1.dev2 botocore \
        aws-requests-auth blinker flask itsdangerous jmespath jsonschema jsonschema-specifications referencing \
        rpds-py progressbar2 python-utils python-xlib urllib3 python-dateutil werkzeug \
        unified-planning fast-downward.translate ConfigSpace more-itertools
    # Fast Downward's wheel (61 MB) is its search binary with debugging symbols: stripped, it packs to 2 MB.
    "$PY" -m pip download --quiet --no-deps --only-binary :all: --python-version 3.12 \
        --platform manylinux_2_28_x86_64 -d "$tmp" up-fast-downward==1.0.0
    "$PY" -m pip install --quiet --target "$tmp/tools" wheel
    PYTHONPATH=$tmp/tools "$PY" -m wheel unpack "$tmp"/up_fast_downward-*.whl -d "$tmp/fd"
    strip "$tmp"/fd/up_fast_downward-*/up_fast_downward/downward/builds/release/bin/downward
    PYTHONPATH=$tmp/tools "$PY" -m wheel pack "$tmp"/fd/up_fast_downward-* -d "$GPU/wheels"
    rm -rf "$tmp"
    du -sh "$GPU"
}

build() {
    local site=$1 tmp
    tmp=$(mktemp -d)
    tar -xzf "$GPU/llama-cpp-python-src.tar.gz" -C "$tmp"
    PYTHONPATH=$site CMAKE_BUILD_PARALLEL_LEVEL=$(nproc) \
        CMAKE_ARGS="-DGGML_CUDA=on -DCMAKE_CUDA_ARCHITECTURES=native -DGGML_CUDA_FA=OFF -DLLAVA_BUILD=OFF" \
        "$PY" -m pip install --quiet --no-build-isolation --no-deps --no-index --target "$site" \
        "$tmp/llama_cpp_python-$LLAMA_CPP_PYTHON"
    rm -rf "$tmp"
}

# A process that loads a model with llama.cpp's own API, numpy imported first unless PROBE_ORDER says otherwise.
PROBE='import os, sys
if os.environ.get("PROBE_ORDER") != "llama-first":
    import numpy
if os.environ.get("PROBE_STDCXX_GLOBAL"):
    import ctypes
    ctypes.CDLL("libstdc++.so.6", mode=ctypes.RTLD_GLOBAL)
import llama_cpp
import numpy
params = llama_cpp.llama_model_default_params()
params.n_gpu_layers = int(os.environ.get("PROBE_LAYERS", "0"))
if os.environ.get("PROBE_NO_EXTRA_BUFTS"):
    params.use_extra_bufts = False
llama_cpp.llama_backend_init()
sys.exit(0 if llama_cpp.llama_model_load_from_file(sys.argv[1].encode(), params) else 3)'

import_order() {
    local model=$1 layers=$2 rc name vars
    echo "numpy before llama_cpp, a model loaded (exit 0: loaded; 139: segmentation fault):"
    while read -r name vars; do
        rc=0; env $vars "$PY" -c "$PROBE" "$model" </dev/null >/dev/null 2>&1 || rc=$?
        echo "  $name: exit $rc"
    done <<VARIANTS
llama_cpp-first PROBE_ORDER=llama-first
numpy-first PROBE_ORDER=numpy-first
numpy-first,all-layers-on-gpu PROBE_LAYERS=$layers
numpy-first,OPENBLAS_CORETYPE=Haswell OPENBLAS_CORETYPE=Haswell
numpy-first,no-extra-buffer-types PROBE_NO_EXTRA_BUFTS=1
numpy-first,no-visible-gpu CUDA_VISIBLE_DEVICES=
numpy-first,libstdc++-made-global PROBE_STDCXX_GLOBAL=1
VARIANTS
    rc=0; "$PY" -c "import numpy, sys
from smartllm_local.planner.backends import load_backend
load_backend('llamacpp', sys.argv[1], n_ctx=512, n_gpu_layers=$layers, prefix_cache='off').close()" "$model" \
        >/dev/null 2>&1 || rc=$?
    echo "  numpy-first,the-project's-load_backend: exit $rc"
    local lib
    for lib in "$(dirname "$("$PY" -c 'import llama_cpp; print(llama_cpp.__file__)')")"/lib/lib{llama,ggml-cuda}.so; do
        [[ -f $lib ]] || continue
        echo "  $(basename "$lib"): needs $(readelf -d "$lib" | grep -o 'NEEDED.*\[.*\]' | grep -o '\[.*\]' | tr -d '[]' \
            | tr '\n' ' '); exports $(nm -D --defined-only "$lib" 2>/dev/null | grep -c ' _ZNS') std:: symbols"
    done
    if command -v cuda-gdb >/dev/null && ! "$PY" -c "$PROBE" "$model" >/dev/null 2>&1; then
        echo "  where numpy-first crashes (cuda-gdb):"
        cuda-gdb -q -batch -ex run -ex bt -ex 'info sharedlibrary' --args "$PY" -c "$PROBE" "$model" 2>&1 \
            | grep -E '^#|signal|openblas|libggml|libllama|libgomp|libcuda' | head -60 | sed 's/^/    /' || true
    fi
}

wait_for() {  # a model file the writer in the background is writing
    while [[ ! -f $1 ]]; do
        kill -0 "$2" 2>/dev/null || [[ -f $1 ]] || { echo "could not write $1"; exit 1; }
        sleep 1
    done
}

# Tasks per minute with K tasks planned at once: the benchmark run on one shape for each K, each from a new
# process and the same prefix store (the shape's plan of kitchen-01 filled it), its wall time in parallel-K.wall.
parallel_runs() {
    local model=$1 layers=$2 work=$3 states=$4 deadline=$5 k began rc
    local -a tasks=()
    for k in ${GPU_CHECK_TASKS:-}; do tasks+=(--task "$k"); done
    for k in $PARALLEL; do
        if [[ $SECONDS -gt $((deadline - 60)) ]]; then
            echo "the benchmark run with --parallel $k left out: $SECONDS s of $deadline gone"
            continue
        fi
        began=$SECONDS rc=0
        # Bounded by the time left, so the tables are printed: a run cut short counts the tasks it scored.
        timeout "$((deadline - 20 - SECONDS))" "$PY" -m smartllm_local benchmark run --model "$model" --n-ctx 4096 \
            --n-gpu-layers "$layers" --prefix-cache "$states" --parallel "$k" "${tasks[@]}" \
            --out "$work/parallel-$k" >"$work/parallel-$k.log" 2>&1 || rc=$?
        echo "$((SECONDS - began))" >"$work/parallel-$k.wall"
        if [[ $rc == 124 ]]; then
            echo "the benchmark run with --parallel $k cut at $((SECONDS - began)) s: the tasks it scored are counted"
        elif [[ $rc != 0 ]]; then
            echo "the benchmark run with --parallel $k failed:"; tail -5 "$work/parallel-$k.log"
        fi
    done
}

run() {
    local cpu=0 layers=-1 work site deadline=${GPU_CHECK_SECONDS:-560}
    local -a shapes
    read -r -a shapes <<<"${GPU_CHECK_SHAPES:-7b}"
    PARALLEL=${GPU_CHECK_PARALLEL:-47 16 4 1}
    if [[ ${1:-} == --cpu ]]; then
        cpu=1; layers=0; shapes=(tiny); PARALLEL=${GPU_CHECK_PARALLEL:-1 2}
        GPU_CHECK_TASKS=${GPU_CHECK_TASKS:-kitchen-01 kitchen-02}
    fi
    work=${OUT:-$(mktemp -d)}
    local gguf=${GGUF_DIR:-/tmp} kept
    kept=$(mktemp -d)
    site=$GPU/site
    grep -m1 'model name' /proc/cpuinfo || true
    echo "CPU AMX flags: $(grep -o -w 'amx[a-z_0-9]*' /proc/cpuinfo | sort -u | tr '\n' ' ')"
    if [[ $cpu == 0 ]]; then
        nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader
        "$PY" -m pip install --quiet --no-deps --no-index --target "$site" "$GPU"/wheels/*.whl
        export PYTHONPATH=$site:$ROOT
    else
        export PYTHONPATH=$ROOT
    fi
    # The models are written while llama.cpp builds (the 70B shape, 38.8 GB, takes about a minute).
    (for shape in tiny "${shapes[@]}"; do
        [[ -f $gguf/random-llama-2-$shape.gguf ]] || "$PY" "$ROOT/scripts/random_gguf.py" --shape "$shape" \
            --out "$gguf/random-llama-2-$shape.gguf" >/dev/null
    done) &
    writer=$!
    trap 'kill "$writer" 2>/dev/null || true' EXIT  # an early exit leaves no writer behind
    if [[ $cpu == 0 ]]; then
        local began=$SECONDS
        build "$site"
        echo "built llama-cpp-python with CUDA in $((SECONDS - began)) s"
    fi
    wait_for "$gguf/random-llama-2-tiny.gguf" "$writer"
    import_order "$gguf/random-llama-2-tiny.gguf" "$layers"
    for shape in "${shapes[@]}"; do
        local model=$gguf/random-llama-2-$shape.gguf
        wait_for "$model" "$writer"
        local began=$SECONDS
        local states=$kept  # a first process's empty prefix store; the first shape's is kept for the runs
        [[ $shape == "${shapes[0]}" ]] || states=$(mktemp -d)
        "$PY" -X faulthandler -m smartllm_local plan --task kitchen-01 --model "$model" --n-ctx 4096 \
            --n-gpu-layers "$layers" --prefix-cache "$states" --out "$work/$shape" \
            >"$work/$shape.log" 2>&1 || { echo "plan on the $shape shape failed:"; tail -20 "$work/$shape.log"; exit 1; }
        echo "$((SECONDS - began))" >"$work/$shape.wall"
        [[ $states == "$kept" ]] || rm -rf "$states"
        if [[ $SECONDS -gt $((deadline - 150)) ]]; then
            echo "the $shape shape's bench left out: $SECONDS s of $deadline gone"
        else
            "$PY" -m smartllm_local bench --models "$model" --n-gpu-layers "$layers" --n-ctx 4096 --sample 2 \
                --no-benchmark --no-executor --out "$work/bench-$shape.json" >>"$work/$shape.log" 2>&1 \
                || { echo "bench on the $shape shape failed:"; tail -20 "$work/$shape.log"; exit 1; }
        fi
        if [[ $shape == "${shapes[0]}" ]]; then
            parallel_runs "$model" "$layers" "$work" "$kept" "$deadline"
            rm -rf "$kept"
        fi
    done
    wait "$writer" || true
    "$PY" "$ROOT/scripts/gpu_table.py" "$work" "${shapes[@]}"
}

case ${1:-} in
    pack) pack ;;
    run) shift; run "$@" ;;
    *) echo "usage: $0 pack | run [--cpu]" >&2; exit 2 ;;
esac
