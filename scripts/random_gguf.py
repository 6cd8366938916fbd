"""Write a random-weight GGUF of a Llama-2 shape (Q4_0, Llama-2's vocabulary), streamed to disk.

Decoding and prompt speed do not depend on the weights, so such a file measures what a real model of that
shape costs on a machine no model can be downloaded to (the lent GPU machines: ``scripts/gpu_check.sh``).
Its plans are noise; the planner's grammars keep them valid plans all the same.

    python scripts/random_gguf.py --shape 7b --out /tmp/llama-2-7b-random.gguf

Needs the ``gguf`` package (the transformers extra has it; llama-cpp-python's source carries it as
``vendor/llama.cpp/gguf-py``).
"""

from __future__ import annotations

import argparse
import lzma
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import gguf
import numpy as np

VOCAB = Path(__file__).resolve().parent.parent / "tests" / "fixtures" / "vocab" / "ggml-vocab-llama-spm.gguf.xz"
Q4_0 = gguf.GGMLQuantizationType.Q4_0
BLOCK, BLOCK_BYTES = gguf.GGML_QUANT_SIZES[Q4_0]  # 32 weights in 18 bytes: an fp16 scale, 16 bytes of nibbles


@dataclass(frozen=True)
class Shape:
    n_embd: int
    n_layer: int
    n_ff: int
    n_head: int
    n_head_kv: int


SHAPES = {
    "tiny": Shape(256, 2, 512, 4, 4),  # for testing the script itself: loads and plans in seconds
    "7b": Shape(4096, 32, 11008, 32, 32),
    "70b": Shape(8192, 80, 28672, 64, 8),
}


def tensors(shape: Shape, n_vocab: int) -> list[tuple[str, int, int]]:
    """(name, rows, columns) of every weight of a Llama-2 of this shape, in llama.cpp's names."""
    kv = shape.n_embd // shape.n_head * shape.n_head_kv
    found = [("token_embd.weight", n_vocab, shape.n_embd), ("output_norm.weight", 1, shape.n_embd),
             ("output.weight", n_vocab, shape.n_embd)]
    for i in range(shape.n_layer):
        block = f"blk.{i}."
        found += [(block + "attn_norm.weight", 1, shape.n_embd), (block + "attn_q.weight", shape.n_embd, shape.n_embd),
                  (block + "attn_k.weight", kv, shape.n_embd), (block + "attn_v.weight", kv, shape.n_embd),
                  (block + "attn_output.weight", shape.n_embd, shape.n_embd),
                  (block + "ffn_norm.weight", 1, shape.n_embd), (block + "ffn_gate.weight", shape.n_ff, shape.n_embd),
                  (block + "ffn_up.weight", shape.n_ff, shape.n_embd),
                  (block + "ffn_down.weight", shape.n_embd, shape.n_ff)]
    return found


def q4_0_rows(rows: int, columns: int, rng: np.random.Generator) -> np.ndarray:
    """Random Q4_0 blocks as bytes (rows, columns / 32 * 18), scaled so that a product keeps its input's size (a
    uniform nibble less 8 has a standard deviation of 4.6): with a fixed scale a 70B shape's activations outgrew
    half precision on a GPU, and its logits were not numbers."""
    blocks = np.empty((rows, columns // BLOCK, BLOCK_BYTES), dtype=np.uint8)
    scale = np.float16(1 / (4.6 * np.sqrt(columns)))
    blocks[..., :2] = np.frombuffer(scale.tobytes(), dtype=np.uint8)
    blocks[..., 2:] = rng.integers(0, 256, size=(rows, columns // BLOCK, BLOCK_BYTES - 2), dtype=np.uint8)
    return blocks.reshape(rows, -1)


def copy_vocabulary(writer: gguf.GGUFWriter, vocab: Path) -> int:
    """Llama-2's tokenizer from llama.cpp's vocabulary-only file; returns the vocabulary's size."""
    with tempfile.TemporaryDirectory() as tmp:
        plain = Path(tmp) / "vocab.gguf"
        plain.write_bytes(lzma.decompress(vocab.read_bytes()))
        reader = gguf.GGUFReader(plain)
        fields = {name: field.contents() for name, field in reader.fields.items() if name.startswith("tokenizer.")}
    tokens = fields.pop("tokenizer.ggml.tokens")
    writer.add_tokenizer_model(fields.pop("tokenizer.ggml.model"))
    writer.add_tokenizer_pre(fields.pop("tokenizer.ggml.pre"))
    writer.add_token_list(tokens)
    writer.add_token_scores(fields.pop("tokenizer.ggml.scores"))
    writer.add_token_types(fields.pop("tokenizer.ggml.token_type"))
    writer.add_bos_token_id(fields.pop("tokenizer.ggml.bos_token_id"))
    writer.add_eos_token_id(fields.pop("tokenizer.ggml.eos_token_id"))
    writer.add_unk_token_id(fields.pop("tokenizer.ggml.unknown_token_id"))
    writer.add_add_bos_token(fields.pop("tokenizer.ggml.add_bos_token"))
    writer.add_add_eos_token(fields.pop("tokenizer.ggml.add_eos_token"))
    return len(tokens)


def write(shape: Shape, out: Path, seed: int = 0, vocab: Path = VOCAB) -> None:
    """The file, tensor by tensor (a 70B shape never has more than one weight in memory)."""
    partial = out.with_name(out.name + ".partial")
    writer = gguf.GGUFWriter(partial, "llama")
    writer.add_name(f"random-llama-2-{shape.n_embd}x{shape.n_layer}")
    writer.add_context_length(4096)
    writer.add_embedding_length(shape.n_embd)
    writer.add_block_count(shape.n_layer)
    writer.add_feed_forward_length(shape.n_ff)
    writer.add_head_count(shape.n_head)
    writer.add_head_count_kv(shape.n_head_kv)
    writer.add_rope_dimension_count(shape.n_embd // shape.n_head)
    writer.add_layer_norm_rms_eps(1e-5)
    writer.add_file_type(gguf.LlamaFileType.MOSTLY_Q4_0)
    n_vocab = copy_vocabulary(writer, vocab)
    weights = tensors(shape, n_vocab)
    for name, rows, columns in weights:
        if rows == 1:
            writer.add_tensor_info(name, (columns,), np.dtype(np.float32), columns * 4)
        else:
            nbytes = rows * columns // BLOCK * BLOCK_BYTES
            writer.add_tensor_info(name, (rows, columns // BLOCK * BLOCK_BYTES), np.dtype(np.uint8), nbytes, Q4_0)
    writer.write_header_to_file()
    writer.write_kv_data_to_file()
    writer.write_ti_data_to_file()
    rng = np.random.default_rng(seed)
    for _name, rows, columns in weights:
        writer.write_tensor_data(np.ones(columns, dtype=np.float32) if rows == 1 else q4_0_rows(rows, columns, rng))
    writer.close()
    partial.replace(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shape", choices=sorted(SHAPES), required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.out.is_dir() or not args.out.parent.is_dir():
        print(f"error: --out {args.out} must be a file in an existing folder", file=sys.stderr)
        return 2
    write(SHAPES[args.shape], args.out, args.seed)
    print(f"written: {args.out} ({args.out.stat().st_size:,} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
