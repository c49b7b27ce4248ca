"""Real PulseView under Xvfb with the wavecheck decoder: ``python -m tools.pulseview_shot``.

A development tool run from a source checkout (not installed). :func:`screenshot` starts a
private Xvfb server and PulseView 0.4.2 on it (``pulseview -c -s SESSION.pvs -i CAPTURE``, its
settings in a temporary ``XDG_CONFIG_HOME``, the decoder from ``SIGROKDECODE_DIR``), waits until
the window stops changing, and grabs it (Pillow's X11 grab). :func:`annotation_rows` finds the
decode trace's annotation rows in a screenshot (for ``tests/wavecheck/sigrok/test_pulseview.py``).

Run as a program it regenerates the README's picture, ``docs/pulseview.png``: the README's trace
of LinuxCNC's stepgen driving a Gecko G202 with 11 us of latency (the command of ``captures/
golden/g202-p20-worst-dirhold.toml`` written as a 1 MHz ``.sr``: :func:`readme_trace`), whole,
at full zoom-out (zoom to fit): its one violation, a DIR hold of 9 us against the G202's 20 us,
is the red box of the Violation regions row, and the Summary row ends in the verdict.
"""

from __future__ import annotations

import argparse
import colorsys
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from wavecheck.capture.edges import Capture
from wavecheck.capture.srzip import write_sr_edges

ROOT = Path(__file__).resolve().parent.parent
PICTURE = ROOT / "docs" / "pulseview.png"
GOLDEN = ROOT / "captures" / "golden" / "g202-p20-worst-dirhold.vcd"


def readme_trace(folder: Path) -> Path:
    """The README's G202 trace (the golden trace's stepgen command, written as ``g202.sr``)."""
    import shlex
    import tomllib

    argv = shlex.split(tomllib.loads(GOLDEN.with_suffix(".toml").read_text())["command"])
    sr = folder / "g202.sr"
    argv[argv.index("-o") + 1] = str(sr)
    run = subprocess.run([sys.executable, "-m", "stepgen", *argv[1:]], capture_output=True,
                         text=True)  # fmt: skip
    if run.returncode != 0:
        raise RuntimeError(f"{shlex.join(argv)}: {run.stderr.strip()}")
    return sr


def sampled_sr(
    capture: Capture, path: Path, rate: int, window: tuple[int, int] | None = None
) -> Path:
    """``capture`` (or its ``window`` of ticks) as a logic analyzer sampling at ``rate`` Hz sees
    it: an edge at time t shows at the first sample at or after t (two edges of a channel in one
    sample cancel); sample 0 is the window's start."""
    lo, hi = window if window is not None else (capture.start, capture.end)
    scale = capture.timebase.tick_s * rate
    num, den = scale.numerator, scale.denominator
    edges, initial = [], []
    for c in capture.channels:
        inside = c.edges[(c.edges >= lo) & (c.edges < hi)]
        before = int(np.count_nonzero(c.edges < lo))
        s = -((-(inside - lo) * num) // den)
        u, n = np.unique(s, return_counts=True)
        s = u[n % 2 == 1]
        first = c.initial ^ (before & 1)
        edges.append(s[s > 0].astype(np.int64))
        initial.append(first ^ int(len(s) > 0 and s[0] == 0))
    n_samples = int(-((-(hi - lo) * num) // den)) + 2
    write_sr_edges(path, [c.name for c in capture.channels], edges, initial, n_samples,
                   samplerate=rate)  # fmt: skip
    return path


def _xvfb(size: str) -> tuple[subprocess.Popen[bytes], str]:
    """A private Xvfb server and its display name."""
    read, write = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write), "-screen", "0", f"{size}x24", "-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    with os.fdopen(read) as fh:
        number = fh.readline().strip()
    if not number:
        server.kill()
        raise RuntimeError("Xvfb did not start")
    return server, f":{number}"


def screenshot(
    capture: Path,
    session: Path,
    decoder_dir: Path,
    *,
    input_format: str | None = None,
    timeout: float = 90.0,
    size: str = "1280x720",
    pointer: tuple[int, int] | None = None,
    keys: str = "",
) -> tuple[object, str]:
    """PulseView's window showing ``capture`` with ``session`` (a PIL image, cropped to the
    window), and PulseView's log. With ``pointer``: once the window has settled, the pointer
    moves there and ``keys`` are typed (``"f"``: zoom to fit), and the window is grabbed once it
    has settled again (PulseView draws annotations put after its last repaint, such as the
    decoder's summary at the end of the input, when it next repaints)."""
    from PIL import ImageChops, ImageGrab

    server, display = _xvfb(size)
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, DISPLAY=display, XDG_CONFIG_HOME=home,
                   SIGROKDECODE_DIR=str(decoder_dir), QT_QPA_PLATFORM="xcb")  # fmt: skip
        # -geometry: Qt's option for the first window (there is no window manager to size it)
        cmd = ["pulseview", "-geometry", f"{size}+0+0", "-c", "-s", str(session)]
        cmd += ["-I", input_format] if input_format else []
        log = Path(home) / "pulseview.log"
        with open(log, "wb") as out:
            viewer = subprocess.Popen([*cmd, "-i", str(capture)], env=env, stdout=out,
                                      stderr=subprocess.STDOUT)  # fmt: skip
        try:
            grab = lambda: ImageGrab.grab(xdisplay=display)  # noqa: E731
            image = _settled(grab, ImageChops, timeout)
            if pointer is not None:  # the pointer moved over the view: PulseView repaints
                _x_input(display, pointer, keys)
                image = _settled(grab, ImageChops, timeout)
        finally:
            viewer.terminate()
            try:
                viewer.wait(10)
            except subprocess.TimeoutExpired:
                viewer.kill()
            server.terminate()
            server.wait(10)
        text = log.read_text(errors="replace")
    box = image.getbbox()  # the window: the rest of the screen is black
    return (image.crop(box) if box else image), text


def _x_input(display: str, pointer: tuple[int, int], keys: str) -> None:
    """Move the X pointer of ``display`` to ``pointer`` and type ``keys`` there (the XTEST
    extension, as a user's mouse and keyboard would: with no window manager, the keyboard
    goes to the window under the pointer)."""
    import ctypes

    x11, xtst = ctypes.CDLL("libX11.so.6"), ctypes.CDLL("libXtst.so.6")
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x11.XFlush.argtypes = x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    x11.XSync.argtypes = [ctypes.c_void_p, ctypes.c_int]
    x11.XDefaultRootWindow.restype = ctypes.c_ulong
    x11.XDefaultRootWindow.argtypes = [ctypes.c_void_p]
    x11.XSetInputFocus.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_ulong]
    ulong_p, int_p = ctypes.POINTER(ctypes.c_ulong), ctypes.POINTER(ctypes.c_int)
    x11.XQueryPointer.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ulong_p, ulong_p, int_p, int_p,
                                  int_p, int_p, ctypes.POINTER(ctypes.c_uint)]  # fmt: skip
    x11.XStringToKeysym.restype = ctypes.c_ulong
    x11.XStringToKeysym.argtypes = [ctypes.c_char_p]
    x11.XKeysymToKeycode.restype = ctypes.c_ubyte
    x11.XKeysymToKeycode.argtypes = [ctypes.c_void_p, ctypes.c_ulong]
    xtst.XTestFakeMotionEvent.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int,
                                          ctypes.c_int, ctypes.c_ulong]  # fmt: skip
    xtst.XTestFakeKeyEvent.argtypes = [ctypes.c_void_p, ctypes.c_uint, ctypes.c_int,
                                       ctypes.c_ulong]  # fmt: skip
    handle = x11.XOpenDisplay(display.encode())
    if not handle:
        raise RuntimeError(f"cannot open X display {display}")
    try:
        xtst.XTestFakeMotionEvent(handle, -1, *pointer, 0)
        x11.XSync(handle, 0)
        time.sleep(0.5)
        if keys:  # the keyboard to the window under the pointer (Qt takes keys once focused)
            root, child, coord, mask = (
                ctypes.c_ulong(),
                ctypes.c_ulong(),
                ctypes.c_int(),
                ctypes.c_uint(),
            )
            x11.XQueryPointer(handle, x11.XDefaultRootWindow(handle), ctypes.byref(root),
                              ctypes.byref(child), *(ctypes.byref(coord) for _ in range(4)),
                              ctypes.byref(mask))  # fmt: skip
            if child.value:
                x11.XSetInputFocus(handle, child, 2, 0)  # RevertToParent, CurrentTime
                x11.XSync(handle, 0)
                time.sleep(0.5)
        for key in keys:
            code = x11.XKeysymToKeycode(handle, x11.XStringToKeysym(key.encode()))
            xtst.XTestFakeKeyEvent(handle, code, 1, 0)
            xtst.XTestFakeKeyEvent(handle, code, 0, 0)
        xtst.XTestFakeMotionEvent(handle, -1, 0, 0, 50)  # away: no hover marker in the picture
        x11.XFlush(handle)
    finally:
        x11.XCloseDisplay(handle)


def _settled(grab, chops, timeout: float):  # type: ignore[no-untyped-def]
    """The screen once it has not changed for two seconds (PulseView started, decoded, drawn)."""
    start = time.monotonic()
    last, since = None, time.monotonic()
    while time.monotonic() - start < timeout:
        time.sleep(0.5)
        now = grab()
        if last is None or chops.difference(now, last).getbbox() is not None:
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= 2.0 and now.getbbox() is not None:
            return now
    return last


def annotation_rows(image, left: float = 0.15) -> list[tuple[int, int, tuple[int, int, int]]]:  # type: ignore[no-untyped-def]
    """The colored horizontal bands of a PulseView screenshot below its logic traces: (top,
    bottom, typical color) of each, top to bottom. An annotation row is drawn as boxes of its
    color; a line counts as colored where at least 1 % of its pixels right of ``left`` × width
    are (saturation > 0.3)."""
    rgb = np.asarray(image.convert("RGB"), dtype=np.float64) / 255
    x0 = int(rgb.shape[1] * left)
    part = rgb[:, x0:, :]
    hi, lo = part.max(axis=2), part.min(axis=2)
    sat = np.where(hi > 0, (hi - lo) / np.maximum(hi, 1e-9), 0)
    colored = (sat > 0.3) & (hi > 0.3)
    share = colored.mean(axis=1)
    bands: list[tuple[int, int, tuple[int, int, int]]] = []
    y, n = 0, len(share)
    while y < n:
        if share[y] < 0.01:
            y += 1
            continue
        top = y
        while y < n and share[y] >= 0.01:
            y += 1
        mask = colored[top:y]
        pixels = part[top:y][mask]
        r, g, b = (float(np.median(pixels[:, k])) for k in range(3))
        h, _, _ = colorsys.rgb_to_hsv(r, g, b)
        bands.append((top, y, (round(r * 255), round(g * 255), round(b * 255))))
        del h
    return bands


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", type=Path, default=PICTURE, help="the PNG to write")
    args = ap.parse_args(argv)
    for tool in ("pulseview", "Xvfb", "sigrok-cli"):
        if shutil.which(tool) is None:
            print(f"needs {tool} (make system-deps)", file=sys.stderr)
            return 2
    from wavecheck.sigrok.install import install

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        install(work / "decoders")
        sr = readme_trace(work)
        pvs = work / "g202.pvs"
        check = [sys.executable, "-m", "wavecheck", "check", str(sr), "--drive", "gecko-g202",
                 "--pulseview", str(pvs)]  # fmt: skip
        subprocess.run(check, check=False, capture_output=True)
        # the pointer over the view (a repaint: the summary at the end of the input), zoom to fit
        image, _ = screenshot(sr, pvs, work / "decoders", pointer=(700, 600), keys="f")
    rows = annotation_rows(image)
    if rows:  # down to the last annotation row, not the empty rest of the window
        image = image.crop((0, 0, image.width, min(image.height, rows[-1][1] + 40)))  # type: ignore[attr-defined]
    args.output.parent.mkdir(parents=True, exist_ok=True)
    image.save(args.output, optimize=True)  # type: ignore[attr-defined]
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
