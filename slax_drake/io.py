"""File helpers shared by every stage: atomic writes (a reader never sees a half-written file, an interrupted
write leaves the old file intact) and a matplotlib figure as PNG bytes."""

from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path


def write_text_atomic(path: Path, text: str) -> None:
    """Writes ``text`` to ``path`` through a temporary file in the same folder and an atomic rename."""
    write_bytes_atomic(path, text.encode())


def figure_png(fig, dpi: int) -> bytes:
    """The matplotlib figure ``fig`` as PNG bytes at ``dpi``; the figure is closed."""
    import io

    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    return buf.getvalue()


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Writes ``data`` to ``path`` through a temporary file in the same folder and an atomic rename,
    so a reader never sees a half-written file and an interrupted write leaves the old file intact.

    An OSError (no permission, full disk, a file where a folder must be) names ``path``, never the hidden
    temporary file."""
    path = Path(path)
    make_parent_folder(path)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as e:
        raise OSError(e.errno, e.strerror, str(path)) from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        set_default_file_mode(tmp)
        os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and e.errno is not None:
            raise OSError(e.errno, e.strerror, str(path)) from None
        raise


def make_parent_folder(path: Path) -> None:
    """Creates the folders above ``path``; a file standing where one of them must be is a NotADirectoryError
    that names it (mkdir itself would only say "File exists")."""
    path = Path(path)
    blocker = file_in_the_way(path)
    if blocker is not None:
        raise NotADirectoryError(errno.ENOTDIR, f"{blocker} is a file, not a folder", str(path))
    path.parent.mkdir(parents=True, exist_ok=True)


def file_in_the_way(path: Path) -> Path | None:
    """The nearest existing folder above ``path`` that is not a folder (a file), or None."""
    for ancestor in Path(path).parents:
        if ancestor.exists():
            return None if ancestor.is_dir() else ancestor
    return None


def os_error_message(e: OSError) -> str:
    """One line for an OSError on a user's path: the path and the reason in words. A folder that cannot be made
    because a file stands in the way says so (the system's words are "File exists" or "Not a directory")."""
    if not e.filename:
        return e.strerror or str(e)
    path = Path(os.fsdecode(e.filename))
    if isinstance(e, (FileExistsError, NotADirectoryError)):
        if isinstance(e, FileExistsError) and path.exists() and not path.is_dir():  # mkdir of a folder
            return f"{path}: is a file, not a folder"
        blocker = file_in_the_way(path)
        if blocker is not None:
            return f"{path}: {blocker} is a file, not a folder"
    return f"{path}: {e.strerror or e}"


def set_default_file_mode(path) -> None:
    """Gives a temporary file (mkstemp makes it 0600) the mode an ordinary new file would get (0666 less the
    umask), so that atomically written outputs are as readable as any other file the user writes."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(path, 0o666 & ~umask)


def plural(n: int, word: str, many: str | None = None) -> str:
    """``n`` and ``word`` in the number it takes, for output lines: "1 motion", "2 motions", "2 pushes",
    "0 suction events". ``many``: the plural when it is not ``word`` + "s" or "es" (after s, x, z, ch, sh)."""
    if n == 1:
        return f"{n} {word}"
    if many is None:
        many = word + ("es" if word.endswith(("s", "x", "z", "ch", "sh")) else "s")
    return f"{n} {many}"


def json_safe(value):
    """``value`` (dicts, lists, numbers, strings, NumPy scalars and arrays) as plain JSON types: a policy's decision log
    holds NumPy scalars, which ``json.dumps`` does not take."""
    import json

    def plain(v):
        return v.tolist() if hasattr(v, "tolist") else str(v)

    return json.loads(json.dumps(value, default=plain))
