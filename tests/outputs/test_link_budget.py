"""The link's budget (galvoscan/outputs/link_budget.py): where a planned job would outrun the
serial line, foretold before any byte is sent. The simulated boards hold the forecast to their
own counters (tests/cli/test_mark.py, tests/test_bench.py)."""

from galvoscan import api
from galvoscan.bench_sim import photo_profile, shaded_picture
from galvoscan.outputs.link_budget import expected_underruns


def test_a_60000_mark_photo_is_foretold_to_stream_at_3_mbaud_not_at_1(tmp_path):
    """The streamer's course, foretold from the plan: a 24 mm photo of some 60,000 marks, with
    the default profile's delays, keeps the queue full at both rates; with quick mirrors only
    at the ULX3S's 3 Mbaud."""
    default, quick = api.default_profile(), photo_profile()
    picture = shaded_picture(tmp_path / "photo.png", 300)
    for profile, at_1_mbaud in ((default, False), (quick, True)):
        job = api.plan(api.Job(photos=[api.Photo(str(picture), width_mm=24, lines="runs")],
                               speed_mm_s=1000), profile).vector_job
        marks = sum(1 for a, b in zip(job.segments, job.segments[1:])
                    if a[0] == "jump" and b[0] == "mark")
        assert 55_000 <= marks <= 65_000
        assert expected_underruns(job, 3_000_000) == []
        [(layer, underruns)] = expected_underruns(job, 1_000_000) or [(None, 0)]
        assert (underruns > marks // 2) == at_1_mbaud and layer is None
