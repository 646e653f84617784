"""The README's picture of meerk40t (docs/meerk40t/meerk40t.png): meerk40t's window with the
galvoscan device chosen, a small job drawn (a rectangle and a line of text, one engrave
operation) and meerk40t's preview of it, the status bar showing the simulated board's state;
made under Xvfb, from a fresh meerk40t profile, so that it comes out the same each time.

It needs an X server without a screen (Xvfb), ImageMagick (``import`` grabs the screen,
``convert`` reduces the picture), the DejaVu fonts (the text's font) and wxPython, which
meerk40t's window is made with. wxPython from PyPI builds for a long time; Debian's is ready
made, for Debian's own Python (``/usr/bin/python3``), so the venv is made with that Python and
sees its packages. On Debian 12, from the repository's root::

    apt-get install -y xvfb python3-wxgtk4.0 imagemagick fonts-dejavu-core
    /usr/bin/python3 -m venv --system-site-packages .guivenv
    .guivenv/bin/pip install -e '.[meerk40t]'
    .guivenv/bin/python docs/meerk40t/screenshot.py

(``.guivenv/`` is in .gitignore.) What it does:

1. starts Xvfb on a display of its own (``-displayfd``), a screen of :data:`SCREEN` pixels;
2. writes a meerk40t profile in a temporary home: no root warning, no tips, no update check,
   the main window and the preview window side by side (:data:`WINDOWS`);
3. runs the ``meerk40t`` program of this venv with a batch of console commands
   (:data:`BATCH`): the galvoscan device started on its simulated board (``link`` ``sim``),
   the job drawn and its operation set, meerk40t's ``simulate`` (its plan and the preview
   window), ``board_status`` each second, which says the board's state on the console once
   the device has made its simulated board (the status bar shows the same), and the scene
   fitted to the main window each second (meerk40t fits it once at its start, before the
   window has its size);
4. when the console has said that the preview is open and the board ready, waits
   :data:`SETTLE_S` for the windows to paint, grabs the screen, and writes it reduced to
   :data:`COLOURS` colours, without dithering (flat colours compress well), as
   docs/meerk40t/meerk40t.png.

The caches (YoWASP's compiled Yosys, the simulated board's compiled model) are the user's own
(``XDG_CACHE_HOME``): the first run compiles them, some minutes; later runs take seconds.
"""

import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path


#: The picture this writes.
OUT = Path(__file__).with_name("meerk40t.png")
#: Xvfb's screen, pixels: the two windows side by side.
SCREEN = (1800, 860)
#: meerk40t's profile: its settings file's sections. The main window at the left
#: (``mainwin_*``), the preview window (meerk40t's Simulation) at its right.
WINDOWS = {
    "/": {"suppress_sudo_warning": "True", "show_tips": "False", "update_check": "0",
          "single_instance_only": "False", "mainwin_pos": "(0, 0)",
          "mainwin_size": "(1100, 860)", "mainwin_maximized": "False"},
    "window/Simulation": {"x": "1100", "y": "0", "width": "700", "height": "860"},
}
#: The console commands meerk40t runs at its start.
BATCH = """\
channel print console
service device start -i galvoscan 0
rect 35mm 30mm 40mm 30mm
linetext 33mm 85mm galvoscan -f DejaVuSans.ttf -s 12mm
operation* delete
element* engrave -s 500 -p 300 frequency 50
simulate
timer.status 0 1 board_status
timer.focus 0 1 -g scene focus -4% -4% 104% 104%
"""
#: What the console says once the preview is open, and once the board is ready.
PREVIEW_OPEN, BOARD_READY = "Window opened: Simulation", "galvoscan: board: ready"
#: How long meerk40t may take to say both (the first run compiles the caches), s.
READY_WITHIN_S = 900
#: How long the windows are given to paint once both are said, s.
SETTLE_S = 3.0
#: The picture's colours.
COLOURS = 64


def fail(message):
    print(f"screenshot: error: {message}", file=sys.stderr)
    sys.exit(1)


def check_tools():
    """The programs and the module this needs, or one line saying what is missing."""
    missing = [tool for tool in ("Xvfb", "import", "convert") if shutil.which(tool) is None]
    if missing:
        fail(f"{', '.join(missing)} not found: apt-get install -y xvfb imagemagick")
    if importlib.util.find_spec("wx") is None:
        fail("wxPython is not in this Python: run this with .guivenv/bin/python (see the "
             "docstring)")
    meerk40t = Path(sys.executable).parent / "meerk40t"
    if not meerk40t.exists():
        fail(f"{meerk40t} not found: .guivenv/bin/pip install -e '.[meerk40t]'")
    return meerk40t


def start_xvfb():
    """Xvfb on a free display: (the process, ``:N``)."""
    read, write = os.pipe()
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0",
                             f"{SCREEN[0]}x{SCREEN[1]}x24", "-nolisten", "tcp"],
                            pass_fds=(write,), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    os.close(write)
    with os.fdopen(read) as said:
        number = said.readline().strip()
    if not number:
        xvfb.kill()
        fail("Xvfb did not start")
    return xvfb, f":{number}"


def write_profile(home):
    """meerk40t's settings file in ``home`` (meerk40t's own place for it on Linux)."""
    folder = home / ".config" / "MeerK40t"
    folder.mkdir(parents=True)
    (folder / "MeerK40t.cfg").write_text("".join(
        f"[{section}]\n" + "".join(f"{key} = {value}\n" for key, value in keys.items()) + "\n"
        for section, keys in WINDOWS.items()))


def watch(process, wanted, log):
    """An event for each line in ``wanted``, set when meerk40t's console says it; every line
    goes to ``log``."""
    events = {line: threading.Event() for line in wanted}

    def read():
        for line in process.stdout:
            log.write(line)
            for text, event in events.items():
                if text in line:
                    event.set()
    threading.Thread(target=read, daemon=True).start()
    return events


def main():
    meerk40t = check_tools()
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    with tempfile.TemporaryDirectory(prefix="galvoscan-screenshot-") as folder:
        folder = Path(folder)
        home = folder / "home"
        write_profile(home)
        (folder / "batch.txt").write_text(BATCH)
        xvfb, display = start_xvfb()
        env = {**os.environ, "DISPLAY": display, "HOME": str(home), "XDG_CACHE_HOME": cache}
        program = subprocess.Popen([str(meerk40t), "-b", "batch.txt"], cwd=folder, env=env,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            with open(folder / "meerk40t.log", "w") as log:
                events = watch(program, (PREVIEW_OPEN, BOARD_READY), log)
                deadline = time.monotonic() + READY_WITHIN_S
                for text, event in events.items():
                    if not event.wait(max(0.0, deadline - time.monotonic())):
                        fail(f"meerk40t never said {text!r} within {READY_WITHIN_S} s")
                time.sleep(SETTLE_S)
                grabbed = folder / "screen.png"
                subprocess.run(["import", "-display", display, "-window", "root",
                                str(grabbed)], check=True)
        finally:
            program.terminate()
            try:
                program.wait(timeout=10)
            except subprocess.TimeoutExpired:
                program.kill()
            xvfb.terminate()
            xvfb.wait()
        subprocess.run(["convert", str(grabbed), "+dither", "-colors", str(COLOURS), "-strip",
                        f"PNG8:{OUT}"], check=True)
    print(f"screenshot: {OUT} ({SCREEN[0]}x{SCREEN[1]}, {COLOURS} colours, "
          f"{OUT.stat().st_size:,} bytes)")


if __name__ == "__main__":
    main()
