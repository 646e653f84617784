"""The stand-alone board of the job player's tests: a small vector build with the player, a
short job and its registers (tests/gateware/player/test_player.py, and both backends in
tests/sim/test_compiled.py)."""

from galvoscan.gateware.top import ScanSettings


#: A small stand-alone build at 4 MHz (2 clocks an XY2 bit), with a 0.2 ms MO lead and a
#: 1 ms debounce, so that a press and a job are a few thousand clocks.
PLAYER_BOARD = dict(clk_freq=4e6, baud=500_000, modes=("vector",), links=("uart",),
                    settings=ScanSettings(mode="vector", run=False), vector_delays=True,
                    correction=None, player=True, mo_lead=0.2e-3, start_debounce_ms=1,
                    vector_queue_depth=8, machine_period_s=1e-6)

JOB = [("jump", 32000, 32000), ("mark", 32300, 32000), ("mark", 32300, 32200),
       ("jump", 33000, 31500), ("mark", 32900, 31700)]
REGISTERS = {"pitch": 60, "pulses_per_point": 1, "laser_power": 120, "jump_delay": 20,
             "laser_on_delay": 10, "laser_off_delay": 20, "mark_delay": 30}
