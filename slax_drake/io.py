"""File helpers shared by every stage: atomic writes (a reader never sees a half-written file, an interrupted
write leaves the old file intact) and a matplotlib figure as PNG bytes."""

from __future__ import annotations

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
    so a reader never sees a half-written file and an interrupted write leaves the old file intact."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        set_default_file_mode(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def set_default_file_mode(path) -> None:
    """Gives a temporary file (mkstemp makes it 0600) the mode an ordinary new file would get (0666 less the
    umask), so that atomically written outputs are as readable as any other file the user writes."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(path, 0o666 & ~umask)
