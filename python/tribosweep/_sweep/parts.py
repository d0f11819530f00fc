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

from . import disk
from .plan import CODE_IDENTITY, Plan

_log = logging.getLogger("tribosweep")


def compare_configs(saved: dict, now: dict, where: str, *, ignore: tuple[str, ...] = ()) -> None:
    """Raise ValueError naming the first difference between a saved and the current configuration
    (keys in ``ignore`` are not compared)."""

    missing = object()

    def show(v):
        if v is missing:
            return "(absent)"
        s = json.dumps(v)
        return s if len(s) < 120 else s[:117] + "..."

    for key in sorted(set(saved) | set(now)):
        a, b = saved.get(key, missing), now.get(key, missing)
        if a == b or key in ignore:
            continue
        if isinstance(a, dict) and isinstance(b, dict):
            for sub in sorted(set(a) | set(b)):
                if a.get(sub, missing) != b.get(sub, missing):
                    raise ValueError(
                        f"cannot resume {where}: {key} {sub!r} differs (saved {show(a.get(sub, missing))}, now "
                        f"{show(b.get(sub, missing))}); use the saved configuration, or delete the directory to "
                        "start over"
                    )
        if key in CODE_IDENTITY:
            raise ValueError(
                f"cannot resume {where}: {key} differs (saved {show(a)}, now {show(b)}): its parts were computed by "
                "other code, whose numbers may differ; resume with that code, delete the directory to start over, "
                "or pass force_resume=True (--force-resume) to mix them (the file then records both)"
            )
        raise ValueError(
            f"cannot resume {where}: {key} differs (saved {show(a)}, now {show(b)}); use the saved "
            "configuration, or delete the directory to start over"
        )


class Parts:
    """The sidecar directory of finished chunks: ``manifest.json`` and ``chunk_NNNNNN.npz``."""

    def __init__(self, output: Path, plan: Plan, resume: bool, *, force: bool = False):
        self.dir = Path(str(output) + ".parts")
        self.plan = plan
        #: The saved code identity when a forced resume accepted another (else None).
        self.forced_from: dict | None = None
        self._lock_fd: int | None = None
        try:
            self._open(output, resume, force)
        except BaseException:
            self.release()
            raise

    def _open(self, output, resume: bool, force: bool) -> None:
        plan = self.plan
        manifest = self.dir / "manifest.json"
        if self.dir.exists():
            self._lock(output)
            if not resume:
                self.release()
                raise FileExistsError(
                    f"{self.dir} holds chunks of an unfinished sweep: pass resume=True (--resume) to finish it, "
                    "or delete the directory to start over"
                )
            try:
                saved = json.loads(manifest.read_text())
            except (OSError, ValueError) as e:
                raise ValueError(f"cannot resume {self.dir}: its manifest is unreadable ({e})") from None
            config = saved.get("config", {})
            compare_configs(config, plan.config, str(self.dir), ignore=CODE_IDENTITY if force else ())
            if any(config.get(k) != plan.config[k] for k in CODE_IDENTITY):
                self.forced_from = {k: config.get(k) for k in CODE_IDENTITY}
                _log.warning("resuming %s across code identities (saved %s, now %s): forced", self.dir,
                             self.forced_from, {k: plan.config[k] for k in CODE_IDENTITY})  # fmt: skip
            self._mend_ledger()
        else:
            self.dir.mkdir()
            self._lock(output)
            try:
                self._atomic_write(manifest, lambda f: f.write(self._manifest_text().encode()))
            except OSError as e:
                if not disk.is_full(e):
                    raise
                self.release()
                shutil.rmtree(self.dir, ignore_errors=True)
                raise disk.DiskFullError(f"no space left on device writing {manifest}: nothing was computed; free "
                                         "space and run the sweep again") from None  # fmt: skip

    def _lock(self, output) -> None:
        """Hold ``lock`` (an exclusive ``flock``) while this sweep writes: a second writer of the same
        output is refused. The system drops it when the process ends, so a crash leaves no stale lock."""
        try:
            import fcntl
        except ImportError:  # not POSIX: no lock
            return
        fd = os.open(self.dir / "lock", os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            other = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise FileExistsError(f"another sweep (process {other}) is writing {output} now: wait for it to finish, "
                                  "or choose another output") from None  # fmt: skip
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, str(os.getpid()).encode(), 0)
        except OSError:  # a full disk: the lock holds all the same
            pass
        self._lock_fd = fd

    def release(self) -> None:
        """Let go of the lock (at the end of the sweep, whatever its outcome)."""
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    @property
    def running(self) -> Path:
        """``running/``: a marker per chunk being computed; one left by a dead process names a suspect."""
        path = self.dir / "running"
        path.mkdir(exist_ok=True)
        return path

    def suspects(self) -> list[int]:
        """Chunks that were being computed when an earlier run's process died (their markers remain)."""
        out = set()
        for p in (self.dir / "running").glob("*_*_*"):
            fields = p.name.split("_")
            if len(fields) != 3 or not all(f.isdigit() for f in fields):
                continue
            k, start, stop = (int(f) for f in fields)
            if k < self.plan.n_chunks and (start, stop) == self.plan.chunk_range(k):
                out.add(k)
        return sorted(out)

    def _mend_ledger(self) -> None:
        """End a ledger torn by a crash or a full disk with a newline, so the next entry starts a line."""
        try:
            with open(self.ledger, "rb+") as f:
                f.seek(0, os.SEEK_END)
                if f.tell():
                    f.seek(-1, os.SEEK_END)
                    if f.read(1) != b"\n":
                        f.write(b"\n")
        except FileNotFoundError:
            pass

    @staticmethod
    def saved_chunk_size(output) -> int | None:
        """The chunk size of the unfinished sweep in ``<output>.parts/`` (None if there is none)."""
        try:
            size = json.loads((Path(str(output) + ".parts") / "manifest.json").read_text())["config"]["chunk_size"]
        except (OSError, ValueError, KeyError, TypeError):
            return None
        return size if isinstance(size, int) and size >= 1 else None

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
        """``checksums.txt``: one line ``k sha256`` per saved part, appended after its rename."""
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
        try:
            self._atomic_write(self.path(k), lambda f: f.write(data))
            # Not fsynced: a ledger line lost in a power cut only makes its part count as unverified,
            # and it is recomputed (the part itself is fsynced before its rename).
            with open(self.ledger, "a") as f:
                f.write(f"{k} {hashlib.sha256(data).hexdigest()}\n")
        except OSError as e:
            if not disk.is_full(e):
                raise
            saved = sum(1 for _ in self.dir.glob("chunk_*.npz"))
            need = int(len(data) / (stop - start) * self.plan.chunk_size * (self.plan.n_chunks - saved))
            raise disk.parts_full(self.path(k), saved, self.plan.n_chunks, self.dir, need,
                                  disk.free_bytes(self.dir)) from None  # fmt: skip

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
        self.release()
        shutil.rmtree(self.dir)


