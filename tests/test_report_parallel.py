"""Figures drawn on two cores: the same files as in turn, and nothing lost when the child fails."""

from __future__ import annotations

import gc
import os

import pytest

from rbhyst.report import parallel


def writer(path, text):
    def job():
        path.write_text(text)
    return job


def test_every_job_runs_once_whichever_process_draws_it(tmp_path, monkeypatch):
    """... and the objects frozen out of the collector's reach for the fork are in it again
    after (a session that draws many runs would otherwise never collect them)."""
    monkeypatch.setattr(parallel, "_fork_is_safe", lambda: True)
    paths = [tmp_path / f"f{k}.txt" for k in range(5)]
    parallel.draw_all([writer(p, str(k)) for k, p in enumerate(paths)])
    assert [p.read_text() for p in paths] == [str(k) for k in range(5)]
    assert gc.get_freeze_count() == 0


def test_what_the_child_does_not_finish_is_drawn_here(tmp_path, monkeypatch):
    monkeypatch.setattr(parallel, "_fork_is_safe", lambda: True)
    parent = os.getpid()
    out = tmp_path / "child_part.txt"

    def fails_in_the_child():
        if os.getpid() != parent:
            raise RuntimeError("a child that dies")
        out.write_text(str(os.getpid()))

    parallel.draw_all([writer(tmp_path / "first.txt", "here"), fails_in_the_child])
    assert out.read_text() == str(parent) and (tmp_path / "first.txt").read_text() == "here"


def test_an_error_in_a_figure_reaches_the_caller(tmp_path, monkeypatch):
    monkeypatch.setattr(parallel, "_fork_is_safe", lambda: True)

    def broken():
        raise ValueError("no such column")

    with pytest.raises(ValueError, match="no such column"):
        parallel.draw_all([writer(tmp_path / "a.txt", "a"), broken])
    assert gc.get_freeze_count() == 0


def test_in_turn_where_forking_is_not_safe(tmp_path, monkeypatch):
    monkeypatch.setattr(parallel, "_fork_is_safe", lambda: False)
    parent = os.getpid()
    seen = []
    parallel.draw_all([lambda: seen.append(os.getpid()) for _ in range(3)])
    assert seen == [parent] * 3
