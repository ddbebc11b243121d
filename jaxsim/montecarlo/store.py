"""Checkpoint folder of a sweep: a manifest with the sweep's fingerprint, and one file per chunk.

Layout of ``DIR``::

    manifest.json                 {"format", "fingerprint", "description", "layout"}   (MANIFEST)
    chunks/p00003_c000012.chunk   one finished chunk (point 3, chunk 12)               (CHUNKS)

Safety rules:

* every file is written atomically: a temporary file in the same folder, ``fsync``, ``os.replace``,
  then ``fsync`` of the folder — a crash (even SIGKILL) leaves either the old state or the new
  file, never half a file under the final name;
* a chunk file is ``MAGIC | sha256(payload) | len(payload) | payload`` (payload: ``.npz`` bytes with
  the chunk's arrays and its metadata); a missing, truncated or corrupt file, or one whose metadata
  does not match, is reported as absent and recomputed — it is never merged;
* the manifest fingerprints everything that determines the result (function name, a hash of the
  per-run computation's jaxpr — operations and constants' values, see
  :mod:`jaxsim.montecarlo.jaxpr_hash` —, parameter space, design, key, run count, block size,
  quantile sketch, ...).  Opening a folder that holds a *different* sweep (the message names what
  differs; an edited per-run function is reported as "the per-run computation changed"), a folder
  that is not a sweep folder, or (without ``resume``) a folder that already holds chunks of this
  sweep raises ``ValueError`` before anything is written.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import struct
from pathlib import Path
from typing import Any

import numpy as np

FORMAT = 1
MANIFEST = "manifest.json"
CHUNKS = "chunks"
MAGIC = b"JXMCCHK1"
_HEADER = len(MAGIC) + 32 + 8
_META_KEY = "__meta__"


def fingerprint_of(description: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON of ``description``."""
    text = json.dumps(description, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory fds
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that ``path`` holds either its old content or all of ``data``."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    with open(tmp, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def encode_chunk(arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> bytes:
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays, **{_META_KEY: np.array(json.dumps(meta, sort_keys=True))})
    payload = buf.getvalue()
    return MAGIC + hashlib.sha256(payload).digest() + struct.pack("<Q", len(payload)) + payload


def decode_chunk(data: bytes) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Inverse of :func:`encode_chunk`; raises ``ValueError`` on any damage."""
    if len(data) < _HEADER or data[: len(MAGIC)] != MAGIC:
        raise ValueError("not a chunk file (bad magic or too short)")
    digest = data[len(MAGIC) : len(MAGIC) + 32]
    (length,) = struct.unpack("<Q", data[len(MAGIC) + 32 : _HEADER])
    payload = data[_HEADER:]
    if len(payload) != length:
        raise ValueError(f"truncated: {len(payload)} of {length} payload bytes")
    if hashlib.sha256(payload).digest() != digest:
        raise ValueError("checksum mismatch")
    with np.load(io.BytesIO(payload), allow_pickle=False) as npz:
        arrays = {k: npz[k] for k in npz.files}
    meta = json.loads(str(arrays.pop(_META_KEY)))
    return arrays, meta


def _different_sweep(root: Path, manifest: dict[str, Any], fingerprint: str, description: dict[str, Any]) -> str:
    """Why ``root`` cannot be opened for this sweep: which parts of the description changed."""
    old = manifest.get("description") if isinstance(manifest.get("description"), dict) else {}
    new = json.loads(json.dumps(description, default=str))  # as the manifest stores it
    changed = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
    if changed == ["computation"]:
        was = str(old.get("computation"))[:12] if old.get("computation") else "not recorded"
        return (
            f"out: the per-run computation changed since the chunks in {root} were written "
            f"(computation hash {was} → {str(new['computation'])[:12]}); nothing was written — to run "
            f"the new code, choose a new folder (without resume=True / --resume) or delete {root}"
        )
    return (
        f"out: {root} holds a different sweep (fingerprint {str(manifest.get('fingerprint'))[:12]}…, "
        f"this sweep {fingerprint[:12]}…; differs in: {', '.join(changed) or 'format'}); "
        "nothing was written — choose another folder or delete that one"
    )


class ChunkStore:
    """The checkpoint folder of one sweep (see module docstring)."""

    def __init__(
        self, root: str | Path, fingerprint: str, description: dict[str, Any], layout: dict[str, Any], resume: bool
    ):
        self.root = Path(root)
        self.fingerprint = fingerprint
        self.chunks_dir = self.root / CHUNKS
        self.rejected: list[tuple[str, str]] = []  # (file name, why) of damaged chunks found
        self._open(description, layout, resume)

    # -- opening ---------------------------------------------------------------------------
    def _open(self, description: dict[str, Any], layout: dict[str, Any], resume: bool) -> None:
        manifest_path = self.root / MANIFEST
        if manifest_path.exists():
            try:
                manifest = json.loads(manifest_path.read_text())
            except (OSError, json.JSONDecodeError) as exc:
                raise ValueError(
                    f"out: {self.root}/manifest.json is unreadable ({exc}); refusing to write into this folder"
                ) from None
            if manifest.get("fingerprint") != self.fingerprint:
                raise ValueError(_different_sweep(self.root, manifest, self.fingerprint, description))
            if manifest.get("layout") != layout:
                raise ValueError(
                    f"chunk_size: {self.root} was written with layout {manifest.get('layout')}, "
                    f"this run asks for {layout}; resume with the same chunk size"
                )
            if not resume and self._chunk_files():
                raise ValueError(
                    f"out: {self.root} already holds {len(self._chunk_files())} chunk(s) of this sweep; "
                    "pass resume=True (CLI: --resume) to continue it, or choose another folder"
                )
            self._remove_stale_temporaries()
            return
        if self.root.exists() and any(self.root.iterdir()):
            raise ValueError(
                f"out: {self.root} exists, is not empty and has no manifest.json "
                "(not a sweep folder); refusing to write into it"
            )
        self.chunks_dir.mkdir(parents=True, exist_ok=True)
        manifest = {"format": FORMAT, "fingerprint": self.fingerprint, "layout": layout, "description": description}
        atomic_write_bytes(manifest_path, (json.dumps(manifest, indent=1, default=str) + "\n").encode())

    def _chunk_files(self) -> list[Path]:
        return sorted(self.chunks_dir.glob("p*_c*.chunk")) if self.chunks_dir.exists() else []

    def _remove_stale_temporaries(self) -> None:
        for tmp in self.chunks_dir.glob(".p*_c*.chunk.tmp-*"):
            tmp.unlink(missing_ok=True)

    # -- chunks ----------------------------------------------------------------------------
    def path(self, point: int, chunk: int) -> Path:
        return self.chunks_dir / f"p{point:05d}_c{chunk:06d}.chunk"

    def save(self, point: int, chunk: int, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        meta = {**meta, "fingerprint": self.fingerprint, "point": point, "chunk": chunk}
        atomic_write_bytes(self.path(point, chunk), encode_chunk(arrays, meta))

    def load(self, point: int, chunk: int, expect: dict[str, Any]) -> dict[str, np.ndarray] | None:
        """The chunk's arrays, or ``None`` if absent or damaged (damage is recorded in ``rejected``)."""
        path = self.path(point, chunk)
        if not path.exists():
            return None
        try:
            arrays, meta = decode_chunk(path.read_bytes())
            want = {**expect, "fingerprint": self.fingerprint, "point": point, "chunk": chunk}
            wrong = {k: (meta.get(k), v) for k, v in want.items() if meta.get(k) != v}
            if wrong:
                raise ValueError(f"metadata mismatch {wrong}")
        except Exception as exc:  # noqa: BLE001 - any damage means: recompute, never merge
            self.rejected.append((path.name, str(exc)))
            return None
        return arrays

    def has(self, point: int, chunk: int) -> bool:
        return self.path(point, chunk).exists()
