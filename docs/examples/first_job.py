"""A first job through galvoscan's Python API (:mod:`galvoscan.api`), without the command line:
a 10 mm square drawn as an SVG here, placed with its centre at (5, -3) mm in the field, planned
for the default machine profile, estimated, and marked on the default bitstream's simulated
board (its compiled backend where a C++ compiler can build it, else Amaranth's); the report is
what the board's XY2-100 wires and laser did.

Run it: ``python docs/examples/first_job.py``.
"""

import tempfile
from pathlib import Path

from galvoscan import api

#: The square's side and where its centre goes, mm.
SIDE_MM = 10.0
CENTRE_MM = (5.0, -3.0)

SVG = f"""<svg xmlns="http://www.w3.org/2000/svg" width="{SIDE_MM}mm" height="{SIDE_MM}mm"
     viewBox="0 0 {SIDE_MM} {SIDE_MM}">
  <rect x="0" y="0" width="{SIDE_MM}" height="{SIDE_MM}" fill="none" stroke="black"/>
</svg>
"""


def main():
    with tempfile.TemporaryDirectory() as folder:
        drawing = Path(folder) / "square.svg"
        drawing.write_text(SVG, encoding="utf-8")
        job = api.Job(drawings=[api.Drawing(str(drawing), offset_mm=CENTRE_MM)],
                      speed_mm_s=1000, power_percent=20)
        plan = api.plan(job)                            # the default machine profile
    print(f"planned: {len(plan.segments)} segments, {plan.mark_mm:.2f} mm marked, "
          f"estimated {plan.estimate_s:.3f} s")
    # The default bitstream's board, as `galvoscan board --sim` simulates it.
    board = api.SimulatedBoard(config=api.PRESETS["default"], backend="auto")
    try:
        report = api.run(plan, board)
    finally:
        board.close()
    marks = report.marks_mm
    print(f"marked: {report.segments} segments, {report.pulses} pulses, "
          f"{'as planned' if report.clean else 'NOT as planned'}")
    print(f"marks: x {marks[:, 0].min():.3f} … {marks[:, 0].max():.3f} mm, "
          f"y {marks[:, 1].min():.3f} … {marks[:, 1].max():.3f} mm")


if __name__ == "__main__":
    main()
