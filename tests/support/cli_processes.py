"""`galvoscan` run as another process, for the tests of a board served on a pseudo-terminal."""

# `python -m galvoscan.cli ARGS --port PORT`, the port read from stdin: the command's imports
# are done before the port is known, so the board (which runs flat out while it is served)
# serves only the command's own work, not its start-up.
CLIENT = """
import runpy, sys
import galvoscan.cli, galvoscan.link.client, galvoscan.gateware.host.regmap, serial
sys.argv = ["galvoscan", *sys.argv[1:], "--port", sys.stdin.readline().strip()]
runpy.run_module("galvoscan.cli", run_name="__main__", alter_sys=True)
"""


# `python -m galvoscan.cli ARGS` stopped by Ctrl-C as from a terminal: a shell that starts the
# tests in the background has them, and so this process, ignore SIGINT (and Python then leaves
# it ignored), where a terminal's Ctrl-C reaches a board started by hand.
BOARD = """
import runpy, signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.argv[0] = "galvoscan"
runpy.run_module("galvoscan.cli", run_name="__main__", alter_sys=True)
"""
