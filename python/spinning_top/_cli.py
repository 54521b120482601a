"""What the package's command lines share (sweep, plot; issue 19): one-line errors naming the
option (`PROG: error: --option: what is wrong`, exit status 2), and output files that are checked
before any work and then written exactly where asked, or not at all.
"""
import argparse
import io
import os
import stat
import sys

#: Exit status of every refusal and failed write (as argparse's own).
USAGE = 2


class UsageError(ValueError):
    """A refusal naming the option: str() is `--option: what is wrong`."""

    def __init__(self, option, message):
        super().__init__(f"{option}: {message}" if option else message)
        self.option = option


def short(value, limit=40, quote=True):
    """A value for a message: its repr (its text if not `quote`), cut to `limit` characters (a
    20 MB value is not echoed)."""
    text = str(value)
    shown = repr(text) if quote else text
    return shown if len(shown) <= limit else f"{shown[:limit]}... ({len(text)} characters)"


def short_path(path):
    """A path for a message: quoted, cut beyond 120 characters (paths are longer than values)."""
    return short(os.fspath(path), 120)


def fail(prog, error):
    """Prints `PROG: error: MESSAGE` (one line, at most ~500 characters) to stderr; returns the
    exit status."""
    message = " ".join(str(error).split("\n"))
    if len(message) > 500:  # a safety net: no message echoes a huge value
        message = f"{message[:500]}... ({len(message)} characters)"
    print(f"{prog}: error: {message}", file=sys.stderr)
    return USAGE


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors in the package's form: `PROG: error: --option: message`
    (argparse prints its usage first and says `argument --option:`)."""

    def __init__(self, *args, error_prog, **kwargs):
        super().__init__(*args, **kwargs)
        self.error_prog = error_prog

    def error(self, message):
        if message.startswith("argument "):
            message = message[len("argument "):]
            # "--workers/-w: ..." -> "--workers: ..."
            head, _, rest = message.partition(": ")
            message = f"{head.split('/')[0]}: {rest}"
        sys.exit(fail(self.error_prog, message))


def whole_number(minimum, maximum=None):
    """An argparse type: a whole number in [minimum, maximum], refused with the value and the bound."""
    def parse(text):
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number >= {minimum}, got {short(text)}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"at most {maximum}, got {short(text, quote=False)}")
        return value
    parse.__name__ = f"whole number >= {minimum}"
    return parse


def extension(path):
    """The lower-case extension of a path without the dot ('' if none)."""
    return os.path.splitext(os.fspath(path))[1][1:].lower()


def figure_formats():
    """matplotlib's formats that save without more software (pgf wants LaTeX; raw and rgba are no
    files to look at): extension -> what it is."""
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()  # a classmethod in every matplotlib 3
    return {ext: name for ext, name in formats.items() if ext not in ("pgf", "raw", "rgba")}


def check_output(option, path, formats):
    """Refuses, before any work, an output that cannot be written as asked: a format other than
    `formats` (extension -> name; no extension is refused too, never guessed), a directory, a
    missing parent directory or one this process may not write into. A device or FIFO that
    exists is written into (as asked); whether it takes the bytes is known only then."""
    path = os.fspath(path)
    ext = extension(path)
    if ext not in formats:
        what = f"extension .{ext}" if ext else "no extension"
        given = ", ".join(f".{e}" for e in formats)
        raise UsageError(option, f"{short_path(path)} has {what}; give one of {given}")
    if os.path.isdir(path):
        raise UsageError(option, f"{short_path(path)} is a directory; give a file name")
    parent = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(parent):
        raise UsageError(option, f"{short_path(path)}: no directory {short_path(parent)}")
    if not os.path.exists(path) and not os.access(parent, os.W_OK | os.X_OK):
        raise UsageError(option, f"{short_path(path)}: cannot create a file in {short_path(parent)} "
                                 "(permission denied)")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise UsageError(option, f"{short_path(path)}: not writable (permission denied)")
    return ext


def write_file(option, path, data):
    """Writes `data` (bytes, rendered whole beforehand) to exactly `path`, in place: a device or
    FIFO is written into, an existing file keeps its links and mode, a file this process may not
    write is not replaced. A failed write raises UsageError naming the option; a regular file
    it had begun to write is removed if this call created it, else left empty, so that no
    partial output passes for a whole one."""
    path = os.fspath(path)
    created = not os.path.lexists(path)
    opened = False
    try:
        with open(path, "wb") as f:
            opened = True
            f.write(data)
    except OSError as error:
        note = ""
        try:
            if opened and stat.S_ISREG(os.stat(path).st_mode):
                if created:
                    os.remove(path)
                else:
                    os.truncate(path, 0)
                    note = " (left empty, not half written)"
        except OSError:
            pass
        raise UsageError(option, f"cannot write {short_path(path)}: {error.strerror or error}{note}") from None


def figure_bytes(figure, fmt, **kwargs):
    """A matplotlib figure rendered in memory in `fmt` (so a file is written whole or not at all)."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format=fmt, **kwargs)
    return buffer.getvalue()
