"""benchmarks/derive.py: the tables are built from real runs (correctness only, no timing assertions)."""

from __future__ import annotations

from benchmark_scripts import load

bench_derive = load("derive")


def test_work_and_command_tables_on_a_small_chain():
    work = bench_derive.work_table((3,), lambda line: None)
    (row,) = work
    assert row["n"] == 3 and row["springs"] > 0 and row["lagrange"] > 0
    assert abs(row["ratio"] - row["lagrange"] / row["springs"]) < 1e-12
    assert row["met"] is None  # the target is stated at N >= 40 only
    commands = bench_derive.command_table((3,), 1, lambda line: None)
    assert commands[0]["modes_wall"] > 0 and commands[0]["derive_cpu"] > 0
    text = bench_derive.markdown(work, commands)
    assert "| 3 |" in text and "LagrangesMethod" in text
