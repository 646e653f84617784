"""The command line's shared parts (``galvoscan/cli/args.py``): every option explained, output
folders made or refused before any work, unreadable inputs one line."""

import argparse

import pytest
from hypothesis import given, strategies as st

from galvoscan.cli import main, parser
from galvoscan.cli.args import int_in, number_in, output_dir, output_file, register_int
from galvoscan.gateware.host.regmap import BY_NAME


def _parsers(top, prefix=("galvoscan",)):
    yield " ".join(prefix), top
    for action in top._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, prefix + (name,))


def test_every_option_has_help():
    missing = []
    for where, p in _parsers(parser()):
        for action in p._actions:
            if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            if not action.help:
                missing.append(f"{where} {'/'.join(action.option_strings) or action.dest}")
    assert not missing, missing


def _one_line_error(capsys, argv):
    with pytest.raises(SystemExit) as exit:
        main(argv)
    assert exit.value.code not in (0, None)
    err = capsys.readouterr().err.strip() or str(exit.value)
    lines = err.splitlines()
    assert "Traceback" not in err
    return lines[-1]


def test_job_that_is_not_utf8_is_one_line(tmp_path, capsys):
    job = tmp_path / "latin1.job"
    job.write_bytes("mark 100 100  # café\n".encode("latin-1"))
    line = _one_line_error(capsys, ["sim", "--mode", "vector", "--job", str(job)])
    assert "not UTF-8" in line and "latin1.job" in line


def test_missing_job_is_one_line(tmp_path, capsys):
    line = _one_line_error(capsys, ["sim", "--mode", "vector", "--job",
                                    str(tmp_path / "nope.job")])
    assert "cannot read the job" in line


@pytest.mark.parametrize("option", ["--csv", "--png", "--vcd"])
def test_output_folder_is_made_before_the_simulation(tmp_path, option, capsys):
    target = tmp_path / "deep" / "er" / ("out.png" if option == "--png" else "out.file")
    # A bad --points value stops the run at once, after the output option was parsed: the
    # folder already exists then, so it is made before any simulation could start.
    _one_line_error(capsys, ["sim", option, str(target), "--points", "0"])
    assert target.parent.is_dir()


def test_output_under_a_file_is_refused_before_work(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    line = _one_line_error(capsys, ["sim", "--points", "8064", "--csv",
                                    str(blocker / "out.csv")])
    assert "cannot make the folder" in line


def test_output_that_is_a_folder_is_refused(tmp_path, capsys):
    line = _one_line_error(capsys, ["export", "verilog", "-o", str(tmp_path)])
    assert "is a folder" in line


def test_build_dir_that_is_a_file_is_refused(tmp_path, capsys):
    blocker = tmp_path / "build"
    blocker.write_text("")
    line = _one_line_error(capsys, ["build", "--build-dir", str(blocker)])
    assert "is a file" in line


def test_output_helpers(tmp_path):
    assert output_file(str(tmp_path / "a" / "b.csv")) == str(tmp_path / "a" / "b.csv")
    assert (tmp_path / "a").is_dir()
    assert output_dir(str(tmp_path / "c" / "d")) == str(tmp_path / "c" / "d")
    assert (tmp_path / "c" / "d").is_dir()


@pytest.mark.parametrize("name", ["dwell", "pitch", "pulses_per_point", "jump_delay"])
def test_register_arguments_take_the_maps_range(name):
    reg = BY_NAME[name]
    parse = register_int(name)
    assert parse(str(reg.low)) == reg.low and parse(str(reg.high)) == reg.high
    for bad in (reg.low - 1, reg.high + 1):
        with pytest.raises(argparse.ArgumentTypeError):
            parse(str(bad))


@given(st.text(max_size=12))
def test_number_types_refuse_junk_with_a_message(text):
    for parse in (int_in(0, 10, "n"), number_in("x", 0, 10)):
        try:
            value = parse(text)
        except argparse.ArgumentTypeError as error:
            assert str(error)
        else:
            assert 0 <= value <= 10


def test_send_checks_every_assignment_before_opening_the_link(capsys):
    # The port does not exist: had the link been opened first, the error would name it.
    line = _one_line_error(capsys, ["send", "--port", "/dev/nonexistent-galvoscan",
                                    "arm=1", "laser_powr=10"])
    assert "laser_powr" in line
    line = _one_line_error(capsys, ["send", "--port", "/dev/nonexistent-galvoscan",
                                    "run=0", "dwell=0"])
    assert "dwell" in line


def test_version(capsys):
    with pytest.raises(SystemExit) as exit:
        main(["--version"])
    assert exit.value.code == 0
    assert capsys.readouterr().out.startswith("galvoscan ")


@pytest.mark.parametrize("argv, message", [
    (["sim", "--points", "5", "--png", "{tmp}/x.bmp"], ".png is usual"),
    (["correct", "synth-photo", "-o", "{tmp}/p.txt"], ".png is usual"),
    (["sim", "--points", "5", "--csv", "/proc/galvoscan-nope.csv"], "cannot"),
    (["export", "verilog", "-o", "{tmp}/" + "x" * 300 + ".v"], "cannot write"),
    (["sim", "--points", "5", "--pitch", "7"], "--pitch is for --mode vector"),
    (["sim", "--points", "5", "--points-csv", "{tmp}/p.csv"], "--points-csv is for --mode"),
    (["regs", "--table-points", "10"], "multiple of 4"),
    (["build", "--clock", "12e6"], "from 16e6 to 275e6"),
])
def test_wrong_arguments_are_one_line_before_any_work(tmp_path, capsys, argv, message):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    line = _one_line_error(capsys, argv)
    assert message in line
    assert not list(tmp_path.iterdir())              # nothing written, nothing left behind


def test_job_with_a_byte_order_mark_reads(tmp_path, capsys):
    # Windows editors start UTF-8 files with a byte-order mark; that is still UTF-8.
    from galvoscan.cli.args import read_text
    job = tmp_path / "bom.job"
    job.write_bytes("\ufeffjump 100 100\n".encode("utf-8"))
    assert read_text(job).startswith("jump")


def test_not_utf8_names_the_line(tmp_path, capsys):
    job = tmp_path / "latin1.job"
    job.write_bytes(b"jump 1 1\nmark 2 2\n# caf\xe9\n")
    line = _one_line_error(capsys, ["sim", "--mode", "vector", "--job", str(job)])
    assert "latin1.job, line 3" in line


@pytest.mark.parametrize("tail", [["--no-such-option"], ["--help-me", "3"]])
def test_argument_errors_are_one_line_for_every_command(capsys, tail):
    """A wrong option, to any command, is one line that names it and where the options are
    listed (not argparse's usage block), exit status 2."""
    for where, _ in _parsers(parser()):
        argv = where.split()[1:] + tail
        with pytest.raises(SystemExit) as exit:
            main(argv)
        err = capsys.readouterr().err
        assert exit.value.code == 2, argv
        assert len(err.strip().splitlines()) == 1 and "usage:" not in err, (argv, err)
        assert "--help` lists the options" in err, (argv, err)


def _commands():
    """Each command's own parser (not a group of them, as ``machine``) with its long options."""
    return [(where, p, sorted(flag for flag in p._option_string_actions if
                              flag.startswith("--") and flag not in ("--help",)))
            for where, p in _parsers(parser()) if not p._subparsers]


def test_a_mistyped_option_gets_the_nearest_and_the_commands_help(capsys):
    """`mark --sped` was left to the top parser: no suggestion, and `galvoscan --help`, which
    does not list mark's options."""
    with pytest.raises(SystemExit) as exit:
        main(["mark", "drawing.svg", "--sped", "100"])
    assert exit.value.code == 2
    assert capsys.readouterr().err == (
        "galvoscan mark: error: unrecognized arguments: --sped 100 (did you mean --speed?) "
        "(`galvoscan mark --help` lists the options)\n")
    with pytest.raises(SystemExit):
        main(["machine", "show", "--machien=m.toml"])
    assert capsys.readouterr().err == (
        "galvoscan machine show: error: unrecognized arguments: --machien=m.toml (did you "
        "mean --machine?) (`galvoscan machine show --help` lists the options)\n")


@given(st.data())
def test_every_commands_mistyped_options_are_one_line_with_its_help(data):
    """Any command, any of its options with a letter dropped inside (not a prefix, which
    argparse takes as the option): one line naming that command's help; a suggestion, when
    there is one, is one of its options."""
    import contextlib
    import io
    where, _, flags = data.draw(st.sampled_from(_commands()), label="command")
    if not flags:
        return
    flag = data.draw(st.sampled_from([f for f in flags if len(f) > 4] or [None]), label="option")
    if flag is None:
        return
    cut = data.draw(st.integers(3, len(flag) - 2), label="letter dropped")
    typo = flag[:cut] + flag[cut + 1:]
    if typo in flags or any(f.startswith(typo) for f in flags):
        return                          # (another option, or one's abbreviation)
    err = io.StringIO()
    with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as exit:
        main(where.split()[1:] + [f"{typo}=1"])
    line, = err.getvalue().splitlines()
    assert exit.value.code == 2
    assert line.startswith(f"{where}: error: ") and line.endswith(
        f"(`{where} --help` lists the options)"), line
    if "did you mean" in line:
        assert line.split("did you mean ")[1].split("?")[0] in flags, line


def test_refusals_have_one_prefix_and_status_and_failed_work_another_status(tmp_path, capsys):
    """argparse's refusal and the command's own (before any work) read alike: the command's
    name, exit status 2. Work that fails once begun (here, the board's port) is status 1."""
    drawing = tmp_path / "square.svg"
    drawing.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" '
                       'viewBox="0 0 10 10"><rect width="5" height="5"/></svg>')
    said = {}
    for name, argv in {"argparse": ["mark", str(drawing), "--speed", "fast"],
                       "command": ["mark", "--estimate"],
                       "work": ["mark", str(drawing), "--port", str(tmp_path / "no-port")]
                       }.items():
        with pytest.raises(SystemExit) as exit:
            main(argv)
        said[name] = exit.value.code, capsys.readouterr().err.splitlines()[-1]
    assert said["argparse"][0] == said["command"][0] == 2 and said["work"][0] == 1
    assert said["argparse"][1].startswith("galvoscan mark: error: argument --speed: ")
    assert said["command"][1] == "galvoscan mark: error: give a drawing (FILE) or something " \
                                 "to make (--text, --code, --image)"
    assert said["work"][1].startswith(f"galvoscan mark: error: cannot open {tmp_path}")
