"""Job files: a job saved with its settings (``mark … --save job.toml``) and run again
(``mark job.toml``): its drawings and their placement, its text, codes and photos, its layers
and the job's own settings, in TOML.

The file holds what the command line gives, under the same names: each key stands for one
``mark`` option and is read by that option's own type (so its range, its words and its
one-line refusal are the option's), a key that is not one named with the nearest that is.
Paths are relative to the job file's folder. The board, the machine profile, serial numbers
and ``--repeat`` are the command line's: they belong to a run, not to the job::

    [job]
    speed = 1000
    power = 30
    hatch = ["0.05,45", "0.05,135"]

    [[drawing]]
    file = "logo.svg"
    offset = [0, 8]

    [[text]]
    text = "SN {serial:04d}"
    font = "hershey"
    height = 3
    at = [-12, -10]
    layer = "Text"

    [[code]]
    kind = "qr"
    data = "https://example.com/{serial}"
    size = 8
    at = [14, -9]

    [[layer]]
    match = "Text"
    speed = 2000
"""

import argparse
import difflib
import os
from enum import Enum
from pathlib import Path

import tomli_w
try:                    # Python 3.11's; tomli, the same parser, before (requires-python 3.9)
    import tomllib  # novermin: tomli below where it is missing
except ImportError:     # pragma: no cover (CI runs 3.11)
    import tomli as tomllib

from ..geometry.fill import Contour, HatchSet
from ..plan.layer_keys import layer_from_table
from .args import fail
from .job_options import OPTIONS, SECTIONS, defaults as option_defaults, option


__all__ = ["is_job_file", "use_job_file", "save_job_file", "content_entries", "SECTIONS"]


#: Tables that may come more than once (``[[text]]``); ``[job]`` once.
_LISTS = ("drawing", "text", "code", "image", "layer")
#: The options whose values are paths, relative to the job file.
_PATHS = ("file", "image")
#: Job files are small: more is not one.
_MAX_BYTES = 1 << 20


def is_job_file(path):
    return path is not None and Path(path).suffix.lower() == ".toml"


def _read(one, value, where):
    """A TOML value as the option ``one`` (a :class:`~.job_options.Option`) reads it;
    ValueError naming ``where``."""
    dest, action = one.dest, one.argparse
    if one.is_flag:                                 # a flag: true or false
        if not isinstance(value, bool):
            raise ValueError(f"{where} must be true or false, not {value!r}")
        return value
    if isinstance(value, bool) or isinstance(value, dict):
        raise ValueError(f"{where} must be a {'list' if dest == 'hatch' else 'value'}, not "
                         f"{value!r}")
    if isinstance(value, list):
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            raise ValueError(f"{where} must be numbers, as [x, y], not {value!r}")
        value = ",".join(repr(float(v)) for v in value)
    text = str(value)
    try:
        parsed = action["type"](text) if action.get("type") else text
    except argparse.ArgumentTypeError as error:
        raise ValueError(f"{where}: {error}") from None
    if action.get("choices") is not None and parsed not in action["choices"]:
        raise ValueError(f"{where} must be one of {', '.join(map(str, action['choices']))}, "
                         f"not {value!r}")
    return parsed


#: The key each table cannot do without.
_NEEDED = {"drawing": "file", "text": "text", "code": "kind", "image": "file"}
_NEEDED_WHAT = {"drawing": "the SVG, DXF or .job, relative to the job file",
                "text": "the text to mark", "code": "qr, datamatrix or code128",
                "image": "the PNG or JPEG, relative to the job file"}


def _entry(section, table, folder, where, folder_name=""):
    """A table as ``{dest: value}``, the options it leaves out at their defaults."""
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table of settings")
    keys = SECTIONS[section]
    entry = {} if section == "job" else {one.dest: one.default for one in keys.values() if one}
    if section != "job":
        needed = _NEEDED[section]
        if needed not in table:
            raise ValueError(f"{where} needs {needed} = … ({_NEEDED_WHAT[section]})")
        entry["_where"] = f"{folder_name} {where}"      # for what goes wrong with it later
    for key, value in table.items():
        if key not in keys and key.replace("-", "_") in _RUN_OPTIONS:
            raise ValueError(f"{where}: {key!r} belongs to a run, not to the job: give "
                             f"--{key.replace('_', '-')} on the command line")
        if key not in keys:
            near = difflib.get_close_matches(key, keys, n=1)
            raise ValueError(f"{where}: {key!r} is not a setting of [{section}]"
                             f"{f' (did you mean {near[0]!r}?)' if near else ''}; its "
                             f"settings: {', '.join(keys)}")
        one = keys[key]
        if one is None:                             # the layer it takes its settings from
            if not isinstance(value, str) or not value.strip():
                raise ValueError(f"{where}.layer must be a layer's name")
            entry["layer"] = value
            continue
        if one.dest == "hatch":
            values = value if isinstance(value, list) and value and \
                isinstance(value[0], str) else [value]
            entry["hatch"] = [_read(one, v, f"{where}.hatch") for v in values]
            continue
        parsed = _read(one, value, f"{where}.{key}")
        if one.dest in _PATHS:
            parsed = str(folder / parsed)
        entry[one.dest] = (not parsed) if one.inverted else parsed
    return entry


def load_job_file(path):
    """``(job, entries, layers)``: the ``[job]`` settings and every other table, by
    section, as ``{dest: value}``; the layers as :class:`~galvoscan.plan.layers.Layer` s
    and their tables. One line (and exit) for anything wrong."""
    path = Path(path)
    try:
        if path.stat().st_size > _MAX_BYTES:
            fail(f"{path}: {path.stat().st_size:,} bytes: not a job file (1 MiB at most)")
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        fail(f"{path}: no such file")
    except IsADirectoryError:
        fail(f"{path}: a folder, not a job file")
    except UnicodeDecodeError:
        fail(f"{path}: not a text file (a job file is TOML, UTF-8)")
    except OSError as error:
        fail(f"{path}: cannot read ({error.strerror})")
    except tomllib.TOMLDecodeError as error:
        fail(f"{path}: not valid TOML ({error})")
    folder = path.parent
    entries, layers, tables = {section: [] for section in _LISTS}, [], []
    job = {}
    try:
        for section, value in data.items():
            if section not in SECTIONS and section != "layer":
                near = difflib.get_close_matches(section, [*SECTIONS, "layer"], n=1)
                shown = section if section.isidentifier() else repr(section)
                raise ValueError(f"[{shown}] is not a section of a job file"
                                 f"{f' (did you mean [{near[0]}]?)' if near else ''}; its "
                                 f"sections: {', '.join([*SECTIONS, 'layer'])}")
            if section == "job":
                job = _entry("job", value, folder, "[job]")
                continue
            tables_here = value if isinstance(value, list) else [value]
            for k, table in enumerate(tables_here, 1):
                where = f"[[{section}]] {k}"
                if section == "layer":
                    layers.append(layer_from_table(table, where))
                    tables.append(table)
                else:
                    entries[section].append(_entry(section, table, folder, where,
                                                   path.name))
    except ValueError as error:
        fail(f"{path}: {error}")
    if not any(entries[s] for s in ("drawing", "text", "code", "image")):
        fail(f"{path}: nothing to mark: no [[drawing]], [[text]], [[code]] or [[image]]")
    return job, entries, layers, tables


#: What a job file holds: with one, these options are the file's, not the command line's
#: (a run may change only its speed, power, PRR and passes): every option a table holds but
#: the drawing's file, and the layers.
_FILE_ONLY = tuple(
    [o.dest for section in ("drawing", "text", "code", "image") for o in OPTIONS
     if o.section == section and o.dest != "file"] + ["layers"] +
    [o.dest for o in OPTIONS if o.section == "job" and
     o.dest not in ("speed", "power", "prr", "passes")])
#: A run's options, not a job's: a job file that names one is told where it goes.
_RUN_OPTIONS = ("port", "spi", "sim", "baud", "timeout", "backend", "machine", "repeat",
                "serial_start", "serial_step", "json", "preview", "estimate", "frame", "save")


def use_job_file(args):
    """When FILE is a job file: its settings into ``args`` (the command line's ``--speed``,
    ``--power``, ``--prr`` and ``--passes`` still win: a run's own choice) and its objects as
    ``args.entries``; else ``args.entries`` from the command line. One line for an option
    that belongs to the file."""
    if not is_job_file(getattr(args, "file", None)):
        args.entries = content_entries(args)
        return
    defaults = option_defaults()
    given = [d for d in _FILE_ONLY if getattr(args, d, None) != defaults.get(d)]
    if given:
        fail(f"{option(given[0]).flag} is the job file's: put it in "
             f"{args.file} (a run may give only --speed, --power, --prr and --passes)")
    job, entries, layers, tables = load_job_file(args.file)
    for dest, value in job.items():
        if dest in ("speed", "power", "prr", "passes") and getattr(args, dest) is not None:
            continue
        if getattr(args, dest, None) == defaults.get(dest):
            setattr(args, dest, value)
    args.job_file, args.file = args.file, None
    args.layers, args.layer_tables = layers, tables
    args.entries = entries


def content_entries(args):
    """The command line's drawing, text, code and photo as job-file entries."""
    def pick(section, first):
        if getattr(args, first, None) is None:
            return []
        dests = [one.dest for one in SECTIONS[section].values() if one]
        return [{d: getattr(args, d) for d in dests if hasattr(args, d)}]
    return {"drawing": pick("drawing", "file"), "text": pick("text", "text"),
            "code": pick("code", "code"), "image": pick("image", "image")}


def _toml(dest, value, folder):
    """An option's value as the job file writes it."""
    if isinstance(value, HatchSet):
        parts = [value.spacing_mm, value.angle_deg, value.step_deg, value.offset_mm]
        while len(parts) > 1 and parts[-1] == 0:
            parts.pop()                     # the defaults left off, as a person writes it
        return ",".join(f"{v:g}" for v in parts)
    if isinstance(value, Contour):
        return f"{value.spacing_mm:g}" + (f",{value.count}" if value.count else "")
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, tuple):
        return [float(v) for v in value]
    if dest in _PATHS:
        path = Path(value).resolve()
        try:
            return os.path.relpath(path, folder.resolve())
        except ValueError:                  # another drive (Windows)
            return str(path)
    return value


def save_job_file(args, path):
    """Write the job ``args`` plan (as ``use_job_file`` left it) to ``path``, a job file."""
    defaults = option_defaults()
    folder = Path(path).parent

    def table(section, entry):
        """A section's entry (``{dest: value}``) as its TOML table: the defaults said by
        saying nothing (a drawing's placement said whole)."""
        out = {}
        for key, one in SECTIONS[section].items():
            dest = one.dest if one else "layer"
            value = entry.get(dest)
            if value is None or value == []:
                continue
            if section != "drawing" and dest not in ("layer", "text", "code") and \
                    value == defaults.get(dest):
                continue
            if dest == "hatch":
                out[key] = [_toml(dest, h, folder) for h in value]
            else:
                out[key] = (not value) if one and one.inverted else _toml(dest, value, folder)
        return out

    job = table("job", {one.dest: getattr(args, one.dest, None)
                        for one in SECTIONS["job"].values()})
    lists = {section: [table(section, e) for e in args.entries.get(section, [])]
             for section in ("drawing", "text", "code", "image")}
    lists["layer"] = [dict(t) for t in getattr(args, "layer_tables", None) or []]
    # Each table of a list as a [[table]] of its own, as a person writes one (tomli-w puts a
    # list of short tables inline).
    text = f"# galvoscan job: `galvoscan mark {path}` marks it\n"
    if job:
        text += "\n" + tomli_w.dumps({"job": job})
    for section, tables in lists.items():
        for one in tables:
            text += f"\n[[{section}]]\n" + tomli_w.dumps(one)
    try:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(text, encoding="utf-8")
    except OSError as error:
        fail(f"{path}: cannot write the job file ({error.strerror})")
