"""Property: whatever a compressed input holds, reading it gives the mesh or image, or raises SpectraceError as one
line. Never another exception, and never more inflated than its header or the overall limit allows.

The inputs are the compressed files spectrace reads, well formed to start with: binary and ASCII PLY meshes
gzipped, bzip2- and xz-compressed, Mitsuba `.serialized` files (versions 3 and 4, single and double precision,
with normals and texture coordinates) and 16-bit PNG images. Each is damaged one or more ways: the compressed bytes
cut short, flipped, spliced with random bytes or followed by junk; or the inflated content changed before it is
compressed again (header counts made huge, zero or negative, property types changed, the body cut or padded, a
bomb of zeros appended), so that the header and the stream disagree. The overall limit is lowered to 4 MiB here,
so that a header declaring more than that is refused as well.

CI runs 300 examples, derandomised, and states how many ran. A longer, random search:
    SPECTRACE_FUZZ_EXAMPLES=100000 python -m pytest -s tests/robustness/test_fuzz_compressed.py
"""

import bz2
import gzip
import lzma
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st

from fuzz_settings import LONG_RUN_EXAMPLES, fuzz_settings
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import load_mesh
from spectrace.io import compressed
from spectrace.io.images import read_picture

EXAMPLES = 300
FUZZ_SETTINGS = fuzz_settings(
    EXAMPLES, [HealthCheck.function_scoped_fixture, HealthCheck.too_slow, HealthCheck.data_too_large], database=None
)
COMPRESSORS = {".gz": gzip.compress, ".bz2": bz2.compress, ".xz": lzma.compress}
LIMIT_MB = 4

rng = np.random.default_rng(11)
VERTICES = rng.uniform(-1, 1, (12, 3))
FACES = rng.integers(0, 12, (10, 3))
UVS = rng.uniform(0, 1, (12, 2))


def _binary_ply() -> bytes:
    header = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 12\nproperty float x\nproperty float y\n"
        b"property float z\nelement face 10\nproperty list uchar int vertex_indices\nend_header\n"
    )
    records = np.zeros(len(FACES), [("n", "u1"), ("i", "<i4", (3,))])
    records["n"], records["i"] = 3, FACES
    return header + VERTICES.astype("<f4").tobytes() + records.tobytes()


def _ascii_ply() -> bytes:
    header = (
        "ply\nformat ascii 1.0\nelement vertex 12\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 10\nproperty list uchar int vertex_indices\nend_header\n"
    )
    body = "".join(f"{x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in VERTICES)
    body += "".join(f"3 {a} {b} {c}\n" for a, b, c in FACES)
    return (header + body).encode()


def _serialized_body(version: int, double: bool, extras: bool) -> bytes:
    flags = (0x2000 if double else 0x1000) | (0x0003 if extras else 0)
    real = "<f8" if double else "<f4"
    body = struct.pack("<I", flags) + (b"mesh\0" if version == 4 else b"")
    body += struct.pack("<QQ", len(VERTICES), len(FACES)) + VERTICES.astype(real).tobytes()
    if extras:
        body += np.tile([0.0, 0.0, 1.0], (len(VERTICES), 1)).astype(real).tobytes()
        body += UVS.astype(real).tobytes()
    return body + FACES.astype("<u4").tobytes()


def _serialized(body: bytes, version: int, stream: bytes | None = None) -> bytes:
    stream = zlib.compress(body) if stream is None else stream
    table = struct.pack("<Q" if version == 4 else "<I", 0) + struct.pack("<I", 1)
    return struct.pack("<HH", 0x041C, version) + stream + table


PNG_PIXELS = rng.integers(0, 65536, (5, 7, 3)).astype(np.uint16)


def encode_png16(samples: np.ndarray) -> bytes:
    """A 16-bit RGB PNG (W3C PNG 3rd edition): big-endian samples, filter type 0 on every row."""
    height, width, _ = samples.shape

    def chunk(kind: bytes, payload: bytes) -> bytes:
        crc = zlib.crc32(payload, zlib.crc32(kind))
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", crc)

    rows = b"".join(b"\0" + samples[y].astype(">u2").tobytes() for y in range(height))
    header = struct.pack(">IIBBBBB", width, height, 16, 2, 0, 0, 0)
    idat = chunk(b"IDAT", zlib.compress(rows))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + idat + chunk(b"IEND", b"")


# ---------------------------------------------------------------- damage

HEADER_VALUES = st.sampled_from(
    [b"0", b"1", b"-1", b"4294967295", b"4294967296", b"99999999999999999999", b"1e9", b"x", b""]
)


@st.composite
def damaged_content(draw, content: bytes) -> bytes:
    """The inflated content changed: a header number replaced, the body cut or padded, a bomb of zeros added."""
    kind = draw(st.sampled_from(["number", "type", "cut", "pad", "bomb", "none"]))
    if kind == "number":
        numbers = [m for m in range(len(content)) if content[m : m + 1].isdigit()][:40]
        if numbers:
            at = draw(st.sampled_from(numbers))
            end = at
            while end < len(content) and content[end : end + 1].isdigit():
                end += 1
            return content[:at] + draw(HEADER_VALUES) + content[end:]
    if kind == "type":
        old = draw(st.sampled_from([b"float", b"uchar", b"int", b"list", b"binary_little_endian", b"ascii"]))
        new = draw(st.sampled_from([b"double", b"char", b"uint", b"ushort", b"float64", b"list", b"bogus"]))
        return content.replace(old, new, 1)
    if kind == "cut":
        return content[: draw(st.integers(min_value=0, max_value=len(content)))]
    if kind == "pad":
        return content + draw(st.binary(min_size=1, max_size=64))
    if kind == "bomb":
        return content + bytes(draw(st.sampled_from([1, 1 << 16, 8 << 20])))
    return content


@st.composite
def damaged_stream(draw, stream: bytes) -> bytes:
    """The compressed bytes damaged: cut short, a byte flipped, random bytes spliced in or appended."""
    kind = draw(st.sampled_from(["cut", "flip", "splice", "append", "none", "none"]))
    at = draw(st.integers(min_value=0, max_value=max(len(stream) - 1, 0)))
    if kind == "cut":
        return stream[:at]
    if kind == "flip" and stream:
        return stream[:at] + bytes([stream[at] ^ draw(st.integers(1, 255))]) + stream[at + 1 :]
    if kind == "splice":
        return stream[:at] + draw(st.binary(min_size=1, max_size=16)) + stream[at:]
    if kind == "append":
        return stream + draw(st.binary(min_size=1, max_size=16))
    return stream


@st.composite
def compressed_cases(draw) -> tuple[str, bytes]:
    """(file name, bytes) of a damaged compressed input."""
    kind = draw(st.sampled_from(["ply", "ply", "serialized", "png"]))
    if kind == "ply":
        suffix = draw(st.sampled_from(sorted(COMPRESSORS)))
        content = draw(damaged_content(_binary_ply() if draw(st.booleans()) else _ascii_ply()))
        return f"mesh.ply{suffix}", draw(damaged_stream(COMPRESSORS[suffix](content)))
    if kind == "serialized":
        version = draw(st.sampled_from([3, 4]))
        body = draw(damaged_content(_serialized_body(version, draw(st.booleans()), draw(st.booleans()))))
        stream = draw(damaged_stream(zlib.compress(body)))
        return "mesh.serialized", _serialized(body, version, stream)
    return "image.png", draw(damaged_stream(encode_png16(PNG_PIXELS)))


# ---------------------------------------------------------------- the property

COUNTS: dict[str, int] = {}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    return tmp_path_factory.mktemp("compressed-fuzz")


def _read(path: Path):
    if path.suffix == ".png":
        return read_picture(path, "screen.image")
    return load_mesh(path, "shapes[0].file")


@pytest.mark.slow  # about 20 s on a loaded two-core machine
@FUZZ_SETTINGS
@given(case=compressed_cases())
def test_a_compressed_input_reads_or_raises_its_own_one_line_error(workspace, monkeypatch, case):
    monkeypatch.setenv(compressed.MAX_INFLATED_ENVIRONMENT, str(LIMIT_MB))
    name, data = case
    path = workspace / f"case{sum(COUNTS.values())}-{name}"
    path.write_bytes(data)
    try:
        _read(path)
    except SpectraceError as error:
        message = str(error)
        assert len(message.splitlines()) == 1 and message.isprintable(), message
        assert str(path) in message or message.startswith(("shapes[0].file", "screen.image")), message
        outcome = "error"
    else:
        outcome = "read"
    kind = name.split(".", 1)[1]
    COUNTS[f"{kind} {outcome}"] = COUNTS.get(f"{kind} {outcome}", 0) + 1


def test_the_undamaged_inputs_read(tmp_path):
    """The bases: each reads back as what was written."""
    for suffix, compress in COMPRESSORS.items():
        for name, content in (("binary", _binary_ply()), ("ascii", _ascii_ply())):
            path = tmp_path / f"{name}.ply{suffix}"
            path.write_bytes(compress(content))
            mesh = load_mesh(path, "shapes[0].file")
            np.testing.assert_allclose(mesh.vertices, VERTICES, atol=1e-6)
            np.testing.assert_array_equal(mesh.faces, FACES)
    for version in (3, 4):
        path = tmp_path / f"v{version}.serialized"
        path.write_bytes(_serialized(_serialized_body(version, True, True), version))
        mesh = load_mesh(path, "shapes[0].file")
        np.testing.assert_array_equal(mesh.vertices, VERTICES)
        np.testing.assert_array_equal(mesh.faces, FACES)
    path = tmp_path / "image.png"
    path.write_bytes(encode_png16(PNG_PIXELS))
    np.testing.assert_array_equal(read_picture(path, "screen.image"), PNG_PIXELS / 65535.0)


def test_fuzz_counts():
    """How many cases ran, by input kind and outcome (shown with -s); at least the setting's number of examples."""
    print(f"\ncompressed inputs: {sum(COUNTS.values())} cases, by outcome {dict(sorted(COUNTS.items()))}")
    if COUNTS:  # the fuzz test ran in this process (it does unless deselected or run on another worker)
        assert sum(COUNTS.values()) >= (LONG_RUN_EXAMPLES or EXAMPLES)
