"""Result files written whole or not at all: write to a temporary name, then rename.

Every file a command writes as its result (JSON reports, checkpoints, datasets, pictures,
videos) goes through this module, so a run killed at any instant leaves either the previous
complete file or the new complete one under the final name, never a torn one. The temporary
lives in the same folder as the target (``os.replace`` is atomic only within one file system)
and carries the target's suffix (writers such as ``cv2.imwrite`` and SB3's ``save`` pick the
format from it); a temporary left behind by a killed run is removed the next time the same
target is written.

Why here: ``configs`` is the one package every layer already imports (``qshape`` included) and
imports nothing of the project, so every layer can use this helper without reaching upward.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

PARTIAL_TAG = ".partial-"
"""Marker in the name of a temporary file or folder (``.<name>.partial-<pid><suffix>``)."""


def partial_path(path: str | Path) -> Path:
    """The temporary name of ``path`` for this process (same folder, same suffix)."""
    p = Path(path)
    return p.with_name(f".{p.stem}{PARTIAL_TAG}{os.getpid()}{p.suffix}")


def clear_partials(path: str | Path) -> None:
    """Remove temporaries of ``path`` left by killed runs (files or folders)."""
    p = Path(path)
    if not p.parent.is_dir():
        return
    for stale in p.parent.glob(f".{p.stem}{PARTIAL_TAG}*{p.suffix}"):
        if stale.is_dir():
            shutil.rmtree(stale, ignore_errors=True)
        else:
            stale.unlink(missing_ok=True)


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write ``path`` through; renamed onto ``path`` on success.

    For writers that take a file name (``torch.save``, ``model.save``, ``cv2.imwrite``,
    ``savefig``)::

        with atomic_path(out / "model.zip") as tmp:
            model.save(tmp)

    The parent folder is created. On an exception the temporary is removed and ``path`` is
    left as it was.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    clear_partials(target)
    tmp = partial_path(target)
    try:
        yield tmp
        _fsync(tmp)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all."""
    write_bytes(path, text.encode("utf-8"))


def write_json(path: str | Path, value: Any, **dumps: Any) -> None:
    """Write ``json.dumps(value, indent=2, **dumps)`` to ``path`` whole or not at all."""
    write_text(path, json.dumps(value, **{"indent": 2, **dumps}))


def write_image(path: str | Path, bgr: Any) -> None:
    """Write a BGR picture with OpenCV (format from the suffix) whole or not at all.

    Raises:
        OSError: OpenCV could not encode the picture.
    """
    import cv2  # noqa: PLC0415 - only the programs that write pictures need OpenCV

    with atomic_path(path) as tmp:
        if not cv2.imwrite(str(tmp), bgr):
            raise OSError(f"cannot write the picture {path}")


@contextlib.contextmanager
def atomic_dir(path: str | Path) -> Iterator[Path]:
    """Yield an empty temporary folder that replaces the folder ``path`` on success.

    A previous folder at ``path`` is moved aside and deleted only after the new one is in
    place, so ``path`` holds the old complete folder, the new complete one, or (if killed
    between the two renames) nothing. On an exception the temporary folder is removed.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    clear_partials(target)
    tmp = partial_path(target)
    tmp.mkdir()
    try:
        yield tmp
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    replace_dir(tmp, target)


def replace_dir(src: str | Path, target: str | Path) -> None:
    """Put the complete folder ``src`` at ``target`` (same file system), replacing any folder.

    The previous folder is renamed aside first and deleted after ``src`` is in place: a kill
    leaves the old folder, the new one, or none at ``target``, never a mixture.
    """
    dst = Path(target)
    dst.parent.mkdir(parents=True, exist_ok=True)
    old = dst.with_name(f".{dst.stem}{PARTIAL_TAG}old-{os.getpid()}{dst.suffix}")
    if dst.exists():
        os.replace(dst, old)
    os.replace(src, dst)
    shutil.rmtree(old, ignore_errors=True)


def append_line(path: str | Path, line: str) -> None:
    """Append one line to a log in a single write.

    A kill leaves at most one torn last line (no newline); it is cut off before the next line is
    appended, so it never merges with a complete one (`complete_lines` skips it on reading).
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    with p.open("ab") as fh:
        end = fh.seek(0, os.SEEK_END)
        if end:
            with p.open("rb") as rd:
                text = rd.read()
            if not text.endswith(b"\n"):
                fh.truncate(text.rfind(b"\n") + 1)
        fh.write((line.rstrip("\n") + "\n").encode("utf-8"))


def complete_lines(path: str | Path) -> list[str]:
    """The non-empty lines of a log that end with a newline (a torn last line is dropped)."""
    p = Path(path)
    if not p.is_file():
        return []
    text = p.read_text(encoding="utf-8")
    lines = text.split("\n")[:-1]  # the part after the last newline is torn or empty
    return [line for line in lines if line.strip()]


__all__ = [
    "PARTIAL_TAG",
    "append_line",
    "atomic_dir",
    "atomic_path",
    "clear_partials",
    "complete_lines",
    "partial_path",
    "replace_dir",
    "write_bytes",
    "write_image",
    "write_json",
    "write_text",
]
