"""The machine profile (``galvoscan/profile/machine.py``) against random input: random documents,
random values of the known keys, random bytes and random edits of the template all load or
give one ProfileError line that names the file, and nothing else escapes."""

import json
import math
import re

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.profile.machine import (DEFAULT_PROFILE_NAME, ProfileError, load_profile,
                                       parse_profile)
from galvoscan.profile.template import profile_text

from profile_files import DEFAULTS, toml


_KNOWN = {s: list(keys) for s, keys in DEFAULTS.items()}
_names = st.one_of(st.sampled_from(sorted({k for keys in _KNOWN.values() for k in keys})),
                   st.text(min_size=1, max_size=12))
_scalars = st.one_of(
    st.integers(min_value=-10 ** 30, max_value=10 ** 30),
    st.sampled_from([0, 1, 10, 20, 50, 100, 200, 300, 1000, 655350, 12_000_000]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=20),
)
_values = st.recursive(_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=3),
    st.dictionaries(_names, inner, max_size=3)), max_leaves=8)


def _toml_key(key):
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def _toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return "nan" if math.isnan(value) else "inf" if value == math.inf else \
            "-inf" if value == -math.inf else repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(map(_toml_value, value)) + "]"
    return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"


_documents = st.dictionaries(
    st.one_of(st.sampled_from(sorted(_KNOWN)), st.text(min_size=1, max_size=10)),
    st.one_of(st.dictionaries(_names, _values, max_size=5), _values),
    max_size=5)


def _document_text(document):
    top = [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in document.items()
           if not isinstance(v, dict)]
    sections = [f"[{_toml_key(k)}]\n" + "".join(f"{_toml_key(key)} = {_toml_value(value)}\n"
                                                for key, value in v.items())
                for k, v in document.items() if isinstance(v, dict)]
    return "".join(line + "\n" for line in top) + "".join(sections)


def _loads_or_one_line_error(text, path=DEFAULT_PROFILE_NAME):
    try:
        return parse_profile(text, path=path)
    except ProfileError as error:
        assert len(str(error).splitlines()) == 1 and str(error).startswith(str(path))
        return None


@settings(max_examples=200, deadline=None)
@given(_documents)
def test_random_documents(document):
    _loads_or_one_line_error(_document_text(document))


@settings(max_examples=200, deadline=None)
@given(st.dictionaries(st.tuples(st.sampled_from(sorted(_KNOWN)), st.sampled_from(
    sorted({k for keys in _KNOWN.values() for k in keys}))), _scalars, max_size=8))
def test_random_values_of_known_keys(entries):
    _loads_or_one_line_error(toml({key: _toml_value(v) for key, v in entries.items()}))


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("profiles")


@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.one_of(st.binary(max_size=300),
                      st.binary(max_size=60).map(lambda b: profile_text().encode() + b)))
def test_random_bytes(folder, data):
    path = folder / "galvoscan.toml"
    path.write_bytes(data)
    try:
        load_profile(path)
    except ProfileError as error:
        assert len(str(error).splitlines()) == 1 and str(error).startswith(str(path))


def test_every_truncation_of_the_template():
    text = profile_text()
    loaded = sum(_loads_or_one_line_error(text[:cut]) is not None for cut in range(len(text)))
    assert loaded > len(text) // 4           # many cuts fall on whole lines or in comments


@settings(max_examples=300, deadline=None)
@given(st.data())
def test_template_with_random_edits(data):
    text = profile_text()
    start = data.draw(st.integers(0, len(text)))
    end = data.draw(st.integers(start, min(len(text), start + 20)))
    insert = data.draw(st.one_of(st.text(max_size=10),
                                 st.sampled_from(["0", "-1", "1e9", "nan", '"x"', "[", "]",
                                                  "=", "\n", "true", "#", "_", "."])))
    _loads_or_one_line_error(text[:start] + insert + text[end:])
