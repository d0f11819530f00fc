"""The resumable store of a sweep: ``<output>.parts/`` with a manifest and one ``.npz`` per finished chunk.

Every file is written atomically (a temporary file, fsync, ``os.replace``), so a crash or a full
disk never leaves a half-written chunk that counts as done; a chunk whose hash or range does not
match the plan is removed and recomputed.
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import os
import shutil
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .plan import Plan

_log = logging.getLogger("tribosweep")


def compare_configs(saved: dict, now: dict, where: str) -> None:
    """Raise ValueError naming the first difference between a saved and the current configuration."""

    missing = object()

    def show(v):
        if v is missing:
            return "(absent)"
        s = json.dumps(v)
        return s if len(s) < 120 else s[:117] + "..."

    for key in sorted(set(saved) | set(now)):
        a, b = saved.get(key, missing), now.get(key, missing)
        if a == b:
            continue
        if isinstance(a, dict) and isinstance(b, dict):
            for sub in sorted(set(a) | set(b)):
                if a.get(sub, missing) != b.get(sub, missing):
                    raise ValueError(
                        f"cannot resume {where}: {key} {sub!r} differs (saved {show(a.get(sub, missing))}, now "
                        f"{show(b.get(sub, missing))}); use the saved configuration, or delete the directory to "
                        "start over"
                    )
        raise ValueError(
            f"cannot resume {where}: {key} differs (saved {show(a)}, now {show(b)}); use the saved "
            "configuration, or delete the directory to start over"
        )


class Parts:
    """The sidecar directory of finished chunks: ``manifest.json`` and ``chunk_NNNNNN.npz``."""

    def __init__(self, output: Path, plan: Plan, resume: bool):
        self.dir = Path(str(output) + ".parts")
        self.plan = plan
        manifest = self.dir / "manifest.json"
        if self.dir.exists():
            if not resume:
                raise FileExistsError(
                    f"{self.dir} holds chunks of an unfinished sweep: pass resume=True (--resume) to finish it, "
                    "or delete the directory to start over"
                )
            try:
                saved = json.loads(manifest.read_text())
            except (OSError, ValueError) as e:
                raise ValueError(f"cannot resume {self.dir}: its manifest is unreadable ({e})") from None
            compare_configs(saved.get("config", {}), plan.config, str(self.dir))
        else:
            self.dir.mkdir()
            self._atomic_write(manifest, lambda f: f.write(self._manifest_text().encode()))

    def _manifest_text(self) -> str:
        p = self.plan
        body = {"hash": p.hash, "n_points": p.n_points, "n_chunks": p.n_chunks, "shape": list(p.shape), "config": p.config}
        return json.dumps(body, indent=1, sort_keys=True)

    def path(self, k: int) -> Path:
        return self.dir / f"chunk_{k:06d}.npz"

    @staticmethod
    def _atomic_write(path: Path, write) -> None:
        # A unique temporary name in the same folder (two writers never share one), fsynced, renamed.
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                write(f)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise

    @property
    def ledger(self) -> Path:
        """``checksums.txt``: one line ``k sha256`` per saved part, appended and fsynced after its rename."""
        return self.dir / "checksums.txt"

    def save(self, k: int, arrays: Mapping[str, np.ndarray]) -> None:
        start, stop = self.plan.chunk_range(k)
        text = [name for name, a in arrays.items() if np.asarray(a).dtype.kind == "U"]
        meta = {"__hash__": np.array(self.plan.hash), "__range__": np.array([start, stop]), "__text__": np.array(text)}
        # Text is stored as UTF-8 bytes: a quarter of numpy's fixed-width unicode.
        arrays = {name: np.char.encode(a, "utf-8") if name in text else a for name, a in arrays.items()}
        buf = io.BytesIO()
        np.savez(buf, **meta, **arrays)
        data = buf.getvalue()
        self._atomic_write(self.path(k), lambda f: f.write(data))
        with open(self.ledger, "a") as f:
            f.write(f"{k} {hashlib.sha256(data).hexdigest()}\n")
            f.flush()
            os.fsync(f.fileno())

    def checksums(self) -> dict[int, str]:
        out: dict[int, str] = {}
        try:
            lines = self.ledger.read_text().splitlines()
        except OSError:
            return out
        for line in lines:
            parts = line.split()
            if len(parts) == 2 and parts[0].isdigit():
                out[int(parts[0])] = parts[1]  # the last entry of a chunk wins (a recomputed part)
        return out

    def load(self, k: int) -> dict[str, np.ndarray]:
        with np.load(self.path(k), allow_pickle=False) as z:
            text = set(z["__text__"].tolist())
            return {name: np.char.decode(z[name], "utf-8") if name in text else z[name]
                    for name in z.files if not name.startswith("__")}  # fmt: skip

    def text_width(self, k: int, name: str) -> int:
        """The longest UTF-8 value (bytes) of text variable ``name`` in part ``k``, read from its header only."""
        with zipfile.ZipFile(self.path(k)) as z, z.open(name + ".npy") as f:
            version = np.lib.format.read_magic(f)
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            _shape, _fortran, dtype = read(f)
        return int(dtype.itemsize)

    def is_done(self, k: int, checksums: Mapping[int, str] | None = None) -> bool:
        """True for a part whose bytes match its checksum in the ledger and that holds this
        configuration's range; any other file (a flipped bit, a foreign file, a torn write) is
        removed, logged and recomputed, never trusted."""
        p = self.path(k)
        if not p.exists():
            return False
        sums = self.checksums() if checksums is None else checksums
        why = ""
        try:
            data = p.read_bytes()
            if sums.get(k) != hashlib.sha256(data).hexdigest():
                why = "its checksum does not match the ledger" if k in sums else "it has no checksum in the ledger"
            else:
                with np.load(io.BytesIO(data), allow_pickle=False) as z:
                    if str(z["__hash__"]) != self.plan.hash or list(z["__range__"]) != list(self.plan.chunk_range(k)):
                        why = "it belongs to another configuration or range"
        except Exception as e:  # noqa: BLE001 - any unreadable file is simply recomputed
            why = f"it is unreadable ({type(e).__name__})"
        if why:
            _log.warning("recomputing %s: %s", p, why)
            p.unlink()
        return not why

    def remove(self) -> None:
        shutil.rmtree(self.dir)


