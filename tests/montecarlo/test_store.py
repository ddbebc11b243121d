"""Checkpoint folders: damaged chunks are recomputed (never merged), foreign folders are refused."""

import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxsim.montecarlo as mc
from jaxsim.montecarlo.store import decode_chunk, encode_chunk
from tests.montecarlo._demo import SPACE, demo_fn

N, CHUNK = 5_000, 2_000  # 3 chunks per point
DESIGN = mc.grid({"fixed": (1.0, 3.0, 2)})


def _run(out=None, **kw):
    return mc.sweep(demo_fn, SPACE, DESIGN, N, 3, chunk_size=CHUNK, out=out, **kw)


def _snapshot(folder):
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _same(a, b):
    for ra, rb in zip(a.points, b.points):
        aa, bb = ra.arrays(), rb.arrays()
        assert all(np.array_equal(aa[k], bb[k], equal_nan=True) for k in aa)


def test_corrupt_and_truncated_chunks_are_recomputed_never_merged(tmp_path):
    out = tmp_path / "sweep"
    first = _run(out)
    assert first.chunks_computed == 6 and first.chunks_loaded == 0
    reference = _run()  # no folder at all
    _same(first, reference)

    chunks = sorted((out / "chunks").glob("*.chunk"))
    assert len(chunks) == 6
    data = chunks[1].read_bytes()
    chunks[1].write_bytes(data[: len(data) // 2])  # truncated
    flipped = bytearray(chunks[3].read_bytes())
    flipped[-10] ^= 0x40
    chunks[3].write_bytes(bytes(flipped))  # one bit flipped
    chunks[4].write_bytes(b"garbage")  # not a chunk at all
    os.remove(chunks[5])  # missing
    (out / "chunks" / f".{chunks[0].name}.tmp-12345").write_bytes(b"half-written")  # a crash's leftover

    resumed = _run(out, resume=True)
    assert resumed.chunks_loaded == 2 and resumed.chunks_computed == 4
    assert sorted(f for f, _ in resumed.rejected_chunks) == sorted(c.name for c in (chunks[1], chunks[3], chunks[4]))
    _same(resumed, reference)
    assert not list((out / "chunks").glob(".*tmp*"))
    again = _run(out, resume=True)  # everything valid now
    assert again.chunks_loaded == 6 and again.chunks_computed == 0 and not again.rejected_chunks
    _same(again, reference)


def test_folders_holding_something_else_are_refused_and_left_untouched(tmp_path):
    out = tmp_path / "sweep"
    _run(out)
    before = _snapshot(out)
    with pytest.raises(ValueError, match="holds a different sweep"):
        mc.sweep(demo_fn, SPACE, DESIGN, N + 1, 3, chunk_size=CHUNK, out=out, resume=True)
    with pytest.raises(ValueError, match="holds a different sweep"):
        mc.sweep(demo_fn, SPACE, DESIGN, N, 4, chunk_size=CHUNK, out=out, resume=True)
    with pytest.raises(ValueError, match="already holds 6 chunk"):
        _run(out)  # same sweep, but resume not asked for
    with pytest.raises(ValueError, match="chunk_size"):
        mc.sweep(demo_fn, SPACE, DESIGN, N, 3, chunk_size=1000, out=out, resume=True)
    assert _snapshot(out) == before

    other = tmp_path / "my_documents"
    other.mkdir()
    (other / "thesis.tex").write_text("precious")
    with pytest.raises(ValueError, match="not a sweep folder"):
        _run(other)
    assert _snapshot(other) == {other.joinpath("thesis.tex").relative_to(other): b"precious"}


def test_chunk_encoding_detects_every_kind_of_damage():
    arrays = {"a": np.arange(5.0), "b": np.array(3)}
    blob = encode_chunk(arrays, {"first_block": 2})
    back, meta = decode_chunk(blob)
    assert meta == {"first_block": 2} and np.array_equal(back["a"], arrays["a"])
    for bad, why in ((blob[:-1], "truncated"), (blob[:20], "not a chunk"), (b"X" + blob[1:], "not a chunk")):
        with pytest.raises(ValueError, match=why):
            decode_chunk(bad)
    flipped = bytearray(blob)
    flipped[60] ^= 1
    with pytest.raises(ValueError, match="checksum"):
        decode_chunk(bytes(flipped))


# -- resume after a code change: the fingerprint covers the computation, not only the function's name

EDITED_N, EDITED_BLOCK, EDITED_CHUNK = 600, 100, 200  # 3 chunks per point
EDITED_SPACE = {"a": mc.normal(1.0, 0.5), "gain": 2.0}


def _metric_from_source(body: str):
    """``metric(key, p)`` defined from source, always as ``study_metrics.metric`` — as if a user
    edited the body of the same function in the same file between two runs."""
    namespace = {"jax": jax, "jnp": jnp}
    exec(compile(f"def metric(key, p):\n    return {body}\n", "study_metrics.py", "exec"), namespace)
    namespace["metric"].__module__ = "study_metrics"
    return namespace["metric"]


V1 = '{"y": p["gain"] * p["a"] + jax.random.normal(key)}'
V2 = '{"y": p["gain"] * p["a"] - jax.random.normal(key)}'  # same name, signature and output layout


def _edited_sweep(fn, out=None, **kw):
    return mc.sweep(
        fn,
        EDITED_SPACE,
        mc.grid({"gain": (1.0, 2.0, 2)}),
        EDITED_N,
        5,
        block_size=EDITED_BLOCK,
        chunk_size=EDITED_CHUNK,
        out=out,
        **kw,
    )


def test_resume_after_the_per_run_function_changed_is_refused_naming_the_change(tmp_path):
    out = tmp_path / "sweep"
    first = _edited_sweep(_metric_from_source(V1), out)
    assert first.chunks_computed == 6
    before = _snapshot(out)
    edited = _metric_from_source(V2)
    assert edited.__module__ + "." + edited.__qualname__ == "study_metrics.metric"
    for resume in (True, False):
        with pytest.raises(
            ValueError,
            match=r"per-run computation changed since the chunks in .*sweep "
            r"were written \(computation hash [0-9a-f]{12} → [0-9a-f]{12}\)",
        ):
            _edited_sweep(edited, out, resume=resume)
    assert _snapshot(out) == before  # nothing merged, nothing written


def test_resume_with_identical_code_loads_the_chunks_and_equals_an_uninterrupted_run(tmp_path):
    out = tmp_path / "sweep"
    _edited_sweep(_metric_from_source(V1), out)
    chunks = sorted((out / "chunks").glob("*.chunk"))
    for c in chunks[1::2]:  # as if killed before these were written
        c.unlink()
    again = _metric_from_source(V1)  # a new function object from the same source
    resumed = _edited_sweep(again, out, resume=True)
    assert resumed.chunks_loaded == 3 and resumed.chunks_computed == 3 and not resumed.rejected_chunks
    _same(resumed, _edited_sweep(again))  # no folder: one uninterrupted run
    other = _edited_sweep(_metric_from_source(V2))
    assert not np.array_equal(other.points[1]["y"].mean, resumed.points[1]["y"].mean)  # the edit matters
