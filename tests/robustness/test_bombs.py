"""Decompression and fan-out bombs: every compressed input is inflated in bounded steps (spectrace.io.compressed)
and the importers' includes are bounded all together (spectrace.io.input_files.Inclusions).

The bombs are real: a gzip PLY, a Mitsuba `.serialized` mesh and a 16-bit PNG whose streams inflate to 1 GiB from
about 1 MB (deflate stores 16 MiB of zeros in 16 KB), and files that each include the next four times (4^12
readings). Each must be refused with one line naming the file, soon and in little memory: the peak resident
memory of the refusing process is read from the kernel (its VmHWM), and of an in-process read from tracemalloc.
The well-formed files the same code reads back are compared with their plain, uncompressed twins."""

import bz2
import gzip
import lzma
import os
import struct
import subprocess
import sys
import tracemalloc
import zlib

import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import load_mesh
from spectrace.io import compressed
from spectrace.io import input_files as inclusions_module

GIB = 1 << 30
ZEROS = b"\0" * (16 << 20)
# The most memory a refusal may take: the interpreter with spectrace imported takes about 60 MB here; inflating
# a bomb whole would take 1 GiB more.
PEAK_LIMIT_MB = 300
PLY_HEADER = (
    b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
)
TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4").tobytes() + b"\x03" + np.array([0, 1, 2], "<i4").tobytes()


def gzip_bomb(prefix: bytes, zero_bytes: int = GIB) -> bytes:
    """A valid gzip file of `prefix` then `zero_bytes` zeros: members of 16 MiB of zeros concatenated (RFC 1952
    allows several members; gunzip reads them as one stream)."""
    member = gzip.compress(ZEROS, compresslevel=9)
    return gzip.compress(prefix) + member * (zero_bytes // len(ZEROS))


def zlib_bomb(prefix: bytes, zero_bytes: int = GIB) -> bytes:
    """A valid zlib stream (RFC 1950) of `prefix` then `zero_bytes` zeros. After a full flush deflate starts
    afresh, so the blocks of every 16 MiB of zeros are the same bytes; Adler-32 over n more zeros keeps its sum
    A and adds n·A to B (modulo 65521)."""
    deflate = zlib.compressobj(9, zlib.DEFLATED, -15)
    head = deflate.compress(prefix) + deflate.flush(zlib.Z_FULL_FLUSH)
    block = deflate.compress(ZEROS) + deflate.flush(zlib.Z_FULL_FLUSH)
    tail = deflate.flush()
    checksum = zlib.adler32(prefix)
    a, b = checksum & 0xFFFF, checksum >> 16
    b = (b + zero_bytes * a) % 65521
    count = zero_bytes // len(ZEROS)
    return b"\x78\xda" + head + block * count + tail + struct.pack(">I", (b << 16) | a)


def test_the_bombs_are_what_they_claim():
    """The bomb builders against zlib's own reading: the prefix, then zeros; counted over a smaller bomb."""
    for bomb, kind in ((gzip_bomb(b"abc", 64 << 20), "gzip"), (zlib_bomb(b"abc", 64 << 20), "zlib")):
        inflater = zlib.decompressobj(wbits=31 if kind == "gzip" else 15)
        data, total, head = bomb, 0, b""
        while data:
            out = inflater.decompress(data, 1 << 24)
            head, total = head or out[:3], total + len(out)
            data = inflater.unconsumed_tail or (inflater.unused_data if kind == "gzip" else b"")
            if inflater.eof and data:
                inflater = zlib.decompressobj(wbits=31)
        assert (head, total) == (b"abc", 3 + (64 << 20)), kind
    assert len(gzip_bomb(b"")) < 1.1e6 and len(zlib_bomb(b"")) < 1.1e6


# ---------------------------------------------------------------- the bounded reader


@pytest.mark.parametrize(
    "kind, compress",
    [("gzip", gzip.compress), ("zlib", zlib.compress), ("bzip2", bz2.compress), ("xz", lzma.compress)],
)
def test_the_bounded_reader_gives_the_stream_and_refuses_one_byte_more(kind, compress):
    rng = np.random.default_rng(3)
    data = rng.integers(0, 256, 200_000, dtype=np.uint8).tobytes() + bytes(300_000) + b"end"
    packed = compress(data)

    def fail(message):
        return SpectraceError(message, where="x")

    assert compressed.inflate(packed, kind, len(data), fail, "declared") == data
    inflater = compressed.BoundedInflater(packed, kind, len(data), fail)
    assert b"".join(iter(lambda: inflater.read(4099), b"")) == data  # small reads across chunk edges
    with pytest.raises(SpectraceError, match=r"^x: inflates to more than the 488\.3 KiB declared"):
        compressed.inflate(packed, kind, len(data) - 1, fail, "declared")
    for cut in (1, len(packed) // 2, len(packed) - 1):
        with pytest.raises(SpectraceError, match=r"^x: (is truncated|its compressed data is damaged)"):
            compressed.inflate(packed[:cut], kind, len(data), fail)


def test_gzip_members_and_zero_padding_read_as_pythons_gzip_reads_them():
    def fail(message):
        return SpectraceError(message, where="x")

    for data in (
        gzip.compress(b"abc") + gzip.compress(b"") + gzip.compress(b"def"),
        gzip.compress(b"abc") + bytes(200_000) + gzip.compress(b"def") + bytes(3),
        gzip.compress(b"abc") + bytes(70_000),
    ):
        assert compressed.inflate(data, "gzip", 100, fail) == gzip.decompress(data)
    with pytest.raises(SpectraceError, match="its compressed data is damaged"):
        compressed.inflate(gzip.compress(b"abc") + b"junk", "gzip", 100, fail)


def test_the_overall_limit_comes_from_the_environment(monkeypatch):
    monkeypatch.setenv(compressed.MAX_INFLATED_ENVIRONMENT, "1.5")
    assert compressed.max_inflated_bytes() == 3 << 19
    for bad in ("0", "-2", "lots", "nan", "inf"):
        monkeypatch.setenv(compressed.MAX_INFLATED_ENVIRONMENT, bad)
        with pytest.raises(SpectraceError, match=r"^SPECTRACE_MAX_INFLATED_MB: must be a positive number of MiB"):
            compressed.max_inflated_bytes()
    monkeypatch.delenv(compressed.MAX_INFLATED_ENVIRONMENT)
    assert compressed.max_inflated_bytes() == 2 * GIB


# ---------------------------------------------------------------- compressed meshes


def _ply(vertex_count: int, faces: np.ndarray, vertices: np.ndarray) -> bytes:
    header = PLY_HEADER.replace(b"vertex 3", f"vertex {vertex_count}".encode())
    header = header.replace(b"face 1", f"face {len(faces)}".encode())
    records = np.zeros(len(faces), [("n", "u1"), ("i", "<i4", (3,))])
    records["n"], records["i"] = 3, faces
    return header + vertices.astype("<f4").tobytes() + records.tobytes()


@pytest.mark.parametrize("suffix, compress", [(".gz", gzip.compress), (".bz2", bz2.compress), (".xz", lzma.compress)])
def test_a_compressed_mesh_reads_as_its_plain_twin(tmp_path, suffix, compress):
    rng = np.random.default_rng(5)
    vertices = rng.uniform(-1, 1, (40, 3))
    faces = rng.integers(0, 40, (60, 3))
    data = _ply(40, faces, vertices)
    (tmp_path / "plain.ply").write_bytes(data)
    (tmp_path / f"packed.ply{suffix}").write_bytes(compress(data))
    plain = load_mesh(tmp_path / "plain.ply", "shapes[0].file")
    packed = load_mesh(tmp_path / f"packed.ply{suffix}", "shapes[0].file")
    np.testing.assert_array_equal(packed.vertices, plain.vertices)
    np.testing.assert_array_equal(packed.faces, plain.faces)


def test_a_damaged_compressed_mesh_names_the_file_not_a_temporary_one(tmp_path):
    path = tmp_path / "broken.ply.gz"
    path.write_bytes(gzip.compress(PLY_HEADER.replace(b"vertex 3", b"vertex 9") + TRIANGLE)[:-12])
    with pytest.raises(SpectraceError) as caught:
        load_mesh(path, "shapes[0].file")
    message = str(caught.value)
    assert message.startswith(f"shapes[0].file: mesh file '{path}'") and "truncated" in message, message
    plain = tmp_path / "short.ply.gz"
    plain.write_bytes(gzip.compress(PLY_HEADER.replace(b"vertex 3", b"vertex 9") + TRIANGLE))
    with pytest.raises(SpectraceError) as caught:
        load_mesh(plain, "shapes[0].file")
    assert str(plain) in str(caught.value) and "spectrace-mesh-" not in str(caught.value), str(caught.value)


def test_archives_are_refused_unopened(tmp_path):
    for name in ("mesh.zip", "mesh.tar.gz", "mesh.tgz", "mesh.tar.bz2"):
        (tmp_path / name).write_bytes(b"PK\x03\x04")
        with pytest.raises(SpectraceError, match=r"is an archive, which is not read"):
            load_mesh(tmp_path / name, "shapes[0].file")


def _peak_of_read(read) -> tuple[str, int]:
    """(the error message, the peak bytes Python allocated) of `read()`, which must raise SpectraceError."""
    tracemalloc.start()
    try:
        with pytest.raises(SpectraceError) as caught:
            read()
        return str(caught.value), tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_a_serialized_mesh_inflating_past_its_header_is_refused_in_little_memory(tmp_path):
    """A .serialized mesh whose header declares one triangle, its stream then 1 GiB of zeros."""
    body = struct.pack("<I", 0x1000) + b"bomb\0" + struct.pack("<QQ", 3, 1)
    body += np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4").tobytes() + np.array([0, 1, 2], "<u4").tobytes()
    stream = struct.pack("<HH", 0x041C, 4) + zlib_bomb(body)
    path = tmp_path / "bomb.serialized"
    path.write_bytes(stream + struct.pack("<QI", 0, 1))
    message, peak = _peak_of_read(lambda: load_mesh(path, "shapes[0].file"))
    assert message.startswith(f"shapes[0].file: mesh file '{path}'"), message
    assert f"inflates to more than the {len(body)} B its header's counts and flags declare" in message, message
    assert peak < 8 * len(stream), f"{peak / 1e6:.1f} MB allocated"  # the file itself is held: ~1 MB


def test_a_serialized_mesh_declaring_more_than_the_overall_limit_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv(compressed.MAX_INFLATED_ENVIRONMENT, "16")
    body = struct.pack("<I", 0x1000) + b"big\0" + struct.pack("<QQ", 10_000_000, 1)
    path = tmp_path / "big.serialized"
    stream = struct.pack("<HH", 0x041C, 4) + zlib_bomb(body, 64 << 20)
    path.write_bytes(stream + struct.pack("<QI", 0, 1))
    message, peak = _peak_of_read(lambda: load_mesh(path, "shapes[0].file"))
    assert "inflates to more than 16.0 MiB, the limit on a compressed input" in message, message
    assert peak < 40 << 20, f"{peak / 1e6:.1f} MB allocated"


def test_a_16_bit_png_inflating_past_its_header_is_refused_in_little_memory(tmp_path):
    from spectrace.io.images import read_picture

    def chunk(kind: bytes, payload: bytes) -> bytes:
        crc = zlib.crc32(payload, zlib.crc32(kind))
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", 4, 4, 16, 2, 0, 0, 0)  # 4x4 RGB at 16 bits: 4 · (1 + 24) = 100 bytes
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib_bomb(b"")) + chunk(b"IEND", b"")
    path = tmp_path / "bomb.png"
    path.write_bytes(png)
    message, peak = _peak_of_read(lambda: read_picture(path, "screen.image"))
    assert message.startswith(f"screen.image: cannot read image '{path}'"), message
    assert "inflates to more than the 100 B its header declares" in message, message
    assert peak < 8 * len(png), f"{peak / 1e6:.1f} MB allocated"


def _checkpoint(path) -> None:
    from spectrace.engine.checkpoint import Checkpoint, RenderIdentity, write_checkpoint
    from spectrace.film.state import RenderState

    film = np.random.default_rng(2).random((16, 4), dtype=np.float32)
    state = RenderState(3, 1.5, {"film": film, "ray_counts": np.full(16, 7, np.uint32)})
    write_checkpoint(path, Checkpoint(RenderIdentity(4, 4, 1, "s", "k"), state, "d"))


def _repacked(source, target, bombs: dict[str, tuple[tuple[int, ...], str]]) -> None:
    """The checkpoint `source` with every member deflated, and the members named in `bombs` replaced by (or
    added as) arrays of zeros of the given shape and type, streamed: never held whole."""
    import zipfile

    from numpy.lib import format as npy

    with zipfile.ZipFile(source) as archive, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as copy:
        for item in archive.namelist():
            if item.removesuffix(".npy") not in bombs:
                copy.writestr(item, archive.read(item))
        for name, (shape, dtype) in bombs.items():
            with copy.open(f"{name}.npy", "w", force_zip64=True) as stream:
                npy.write_array_header_2_0(stream, {"descr": dtype, "fortran_order": False, "shape": shape})
                for _ in range(int(np.prod(shape)) * np.dtype(dtype).itemsize // len(ZEROS)):
                    stream.write(ZEROS)


@pytest.mark.slow
def test_a_checkpoint_member_inflating_past_its_role_is_refused_unread(tmp_path):
    from spectrace.engine.checkpoint import read_checkpoint

    _checkpoint(tmp_path / "state.npz")
    _repacked(tmp_path / "state.npz", tmp_path / "deflated.npz", {})
    original, deflated = read_checkpoint(tmp_path / "state.npz"), read_checkpoint(tmp_path / "deflated.npz")
    for name, array in original.state.buffers.items():
        np.testing.assert_array_equal(deflated.state.buffers[name], array)
    # 64 MiB bombs, a thousand times their bounds (smaller than the others, to spare CI the deflating).
    cases = {
        "state_film": (((1 << 22, 4), "<f4"), "would inflate to 64.0 MiB, more than 64.2 KiB (what a 4x4 film's"),
        "seed": (((1 << 23,), "<i8"), "member 'seed.npy' would inflate to 64.0 MiB, more than 1 MiB"),
        "state_bogus": (((1 << 24,), "<f4"), "more than 1.0 MiB (what a member other than a known film buffer"),
    }
    for member, (bomb, expected) in cases.items():
        path = tmp_path / f"{member}.npz"
        _repacked(tmp_path / "state.npz", path, {member: bomb})
        assert os.path.getsize(path) < 0.2e6
        message, peak = _peak_of_read(lambda path=path: read_checkpoint(path))
        assert message.startswith(f"{path}: damaged checkpoint: ") and expected in message, message
        assert peak < 8 << 20, f"{peak / 1e6:.1f} MB allocated"


# ---------------------------------------------------------------- the command line: exit status and peak memory

# The command line run as a user runs it, reporting its own peak resident memory (kB) on the last line: VmHWM, the
# peak of this process image. ru_maxrss would keep the peak of the pytest worker that forked it (621 MB seen for a
# child whose own peak was 56 MB).
_MEASURED = (
    "import runpy, sys\n"
    "sys.argv = ['spectrace', *sys.argv[1:]]\n"
    "try:\n"
    "    runpy.run_module('spectrace', run_name='__main__')\n"
    "finally:\n"
    "    peak = next(line.split()[1] for line in open('/proc/self/status') if line.startswith('VmHWM:'))\n"
    "    print(peak, file=sys.stderr)\n"
)


def run_measured(*args: str, cwd) -> tuple[int, list[str], float]:
    """(exit status, stderr lines but the last, peak resident memory in MB) of `spectrace ARGS`."""
    result = subprocess.run(
        [sys.executable, "-c", _MEASURED, *args], capture_output=True, text=True, cwd=cwd, timeout=300
    )
    *lines, peak = result.stderr.splitlines()
    return result.returncode, lines, int(peak) / 1024


PBRT_HEADER = 'LookAt 0 0 5 0 0 0 0 1 0\nCamera "perspective"\nFilm "rgb" "integer xresolution" 8\nWorldBegin\n'


@pytest.mark.subprocess
def test_a_gzip_ply_bomb_is_one_line_and_small_on_the_command_line(tmp_path):
    (tmp_path / "bomb.ply.gz").write_bytes(gzip_bomb(PLY_HEADER + TRIANGLE))
    (tmp_path / "scene.pbrt").write_text(PBRT_HEADER + 'Shape "plymesh" "string filename" "bomb.ply.gz"\n')
    (tmp_path / "out.toml").write_text("# kept\n")
    status, lines, peak_mb = run_measured("import-pbrt", "scene.pbrt", "-o", "out.toml", cwd=tmp_path)
    assert status == 2 and len(lines) == 1, lines
    assert lines[0] == (
        "error: scene.pbrt:5: mesh file 'bomb.ply.gz' (gzip) inflates to more than the 1.2 KiB its PLY header "
        "declares (damaged, or a decompression bomb)"
    )
    assert peak_mb < PEAK_LIMIT_MB, f"peak {peak_mb:.0f} MB"
    assert (tmp_path / "out.toml").read_text() == "# kept\n"


def _fan_out(folder, name: str, body, levels: int = 12, copies: int = 4) -> None:
    """Files 0..levels-1, each including the next `copies` times: copies^levels readings in all."""
    for level in range(levels):
        inner = body(f"{name}{level + 1}") * copies if level < levels - 1 else ""
        (folder / f"{name}{level}").write_text(inner if name.endswith("pbrt") else f"<scene>{inner}</scene>")


@pytest.mark.slow  # 10,000 file readings in each of two processes: about 10 s on a loaded two-core machine
@pytest.mark.subprocess
def test_include_fan_outs_are_one_line_on_the_command_line(tmp_path):
    _fan_out(tmp_path, "f.pbrt", lambda file: f'Include "{file}"\n')
    (tmp_path / "scene.pbrt").write_text(PBRT_HEADER + 'Import "f.pbrt0"\n')
    _fan_out(tmp_path, "f.xml", lambda file: f'<include filename="{file}"/>')
    (tmp_path / "scene.xml").write_text(
        '<scene version="3.0.0"><sensor type="perspective"/><include filename="f.xml0"/></scene>'
    )
    limit = inclusions_module.MAX_INCLUDED_FILES
    for command, scene in (("import-pbrt", "scene.pbrt"), ("import-mitsuba", "scene.xml")):
        status, lines, peak_mb = run_measured(command, scene, "-o", "out.toml", cwd=tmp_path)
        assert status == 2 and len(lines) == 1, lines
        assert f"the scene reads more than {limit} files through" in lines[0], lines
        assert lines[0].startswith("error: f.") and "(a file counts each time it is included)" in lines[0], lines
        assert peak_mb < PEAK_LIMIT_MB, f"peak {peak_mb:.0f} MB"
        assert not (tmp_path / "out.toml").exists()


def test_running_out_of_memory_in_an_import_does_not_blame_the_film(tmp_path, monkeypatch, capsys):
    from cli_runner import run_in_process

    def exhausted(*_):
        raise MemoryError

    (tmp_path / "mesh.ply.gz").write_bytes(gzip.compress(PLY_HEADER + TRIANGLE))
    (tmp_path / "scene.pbrt").write_text(PBRT_HEADER + 'Shape "plymesh" "string filename" "mesh.ply.gz"\n')
    monkeypatch.setattr(compressed.BoundedInflater, "read", exhausted)
    argv = ["import-pbrt", str(tmp_path / "scene.pbrt"), "-o", str(tmp_path / "out.toml")]
    status, stderr = run_in_process(monkeypatch, capsys, argv)
    assert status == 2 and stderr == (
        "error: out of host memory (the scene's meshes, images and included files are more than this machine holds)\n"
    )


# ---------------------------------------------------------------- includes, in process


def test_a_pbrt_include_cycle_is_refused_naming_the_chain(tmp_path):
    from spectrace.interop.pbrt.parser import parse_directives

    (tmp_path / "a.pbrt").write_text('AttributeBegin\nInclude "b.pbrt"\nAttributeEnd\n')
    (tmp_path / "b.pbrt").write_text('Import "a.pbrt"\n')
    (tmp_path / "scene.pbrt").write_text('Include "a.pbrt"\n')
    with pytest.raises(SpectraceError) as caught:
        parse_directives(tmp_path / "scene.pbrt")
    assert (
        str(caught.value)
        == f"{tmp_path / 'b.pbrt'}:1: '{tmp_path / 'a.pbrt'}' includes itself (a.pbrt -> b.pbrt -> a.pbrt)"
    )


def test_the_included_text_is_bounded_in_bytes(tmp_path, monkeypatch):
    """Each reading counts: one 600-byte file read three times passes a 1500-byte budget on its third reading."""
    from spectrace.interop.mitsuba.tree import read_scene as read_mitsuba
    from spectrace.interop.pbrt.parser import parse_directives

    monkeypatch.setattr(inclusions_module, "MAX_INCLUDED_BYTES", 1500)
    (tmp_path / "part.pbrt").write_text("AttributeBegin AttributeEnd\n" * 22)
    (tmp_path / "scene.pbrt").write_text('Include "part.pbrt"\n' * 3)
    with pytest.raises(SpectraceError, match=r"scene.pbrt:3: '.*part.pbrt': the scene's files come to more than"):
        parse_directives(tmp_path / "scene.pbrt")
    (tmp_path / "part.xml").write_text("<scene>" + "<integer name='x' value='1'/>" * 20 + "</scene>")
    (tmp_path / "scene.xml").write_text("<scene>" + '<include filename="part.xml"/>' * 3 + "</scene>")
    with pytest.raises(SpectraceError, match=r"scene.xml: include\[2\]@filename \(line 1\): .*more than 0 MiB"):
        read_mitsuba(tmp_path / "scene.xml", {})


def test_a_gzipped_pbrt_file_reads_as_its_plain_twin(tmp_path, monkeypatch):
    from spectrace.interop.pbrt.parser import parse_directives

    text = 'Shape "sphere" "float radius" 2\nAttributeBegin\nTranslate 1 2 3\nAttributeEnd\n'
    (tmp_path / "part.pbrt").write_text(text)
    (tmp_path / "part.pbrt.gz").write_bytes(gzip.compress(text.encode()))
    (tmp_path / "plain.pbrt").write_text('Include "part.pbrt"\n')
    (tmp_path / "packed.pbrt").write_text('Include "part.pbrt.gz"\n')

    def shown(path):
        return [(d.name, d.arguments, [(p.name, p.values) for p in d.parameters]) for d in parse_directives(path)]

    assert shown(tmp_path / "packed.pbrt") == shown(tmp_path / "plain.pbrt") != []
    (tmp_path / "bomb.pbrt.gz").write_bytes(gzip_bomb(b"WorldBegin\n", 64 << 20))
    (tmp_path / "bombed.pbrt").write_text('Include "bomb.pbrt.gz"\n')
    original = inclusions_module.MAX_INCLUDED_BYTES
    try:
        inclusions_module.MAX_INCLUDED_BYTES = 1 << 20
        message, peak = _peak_of_read(lambda: parse_directives(tmp_path / "bombed.pbrt"))
    finally:
        inclusions_module.MAX_INCLUDED_BYTES = original
    assert message.startswith(f"{tmp_path / 'bombed.pbrt'}:1: pbrt scene file '{tmp_path / 'bomb.pbrt.gz'}' (gzip) "), (
        message
    )
    assert "inflates to more than the 1024.0 KiB left of what a scene's included files may hold" in message, message
    assert peak < 8 << 20, f"{peak / 1e6:.1f} MB allocated"
    assert os.path.getsize(tmp_path / "bomb.pbrt.gz") < 1 << 20
