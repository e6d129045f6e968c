import os

import pytest

from skatetrace.io import atomic_write


def test_atomic_write_replaces_whole_file(tmp_path):
    p = tmp_path / "a.json"
    atomic_write(p, "old")
    atomic_write(p, "new")
    assert p.read_text() == "new"
    assert os.listdir(tmp_path) == ["a.json"]


def test_interrupted_write_keeps_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    p = tmp_path / "a.json"
    atomic_write(p, "old")

    def boom(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(p, "new")
    assert p.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.json"]


def test_result_records_every_tracer_setting():
    from dataclasses import asdict

    import skatetrace as st
    from skatetrace.io import result_dict

    options = st.TraceOptions(speed=1.5, placement="first", search=3)
    d = result_dict(st.trace_figure(st.pattern("circle"), options=options))
    assert d["options"] == asdict(options)
