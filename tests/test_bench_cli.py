"""``emscatter bench``: lists the benchmarks, rejects unknown names (no benchmark is run here:
performance targets live in benchmarks/, not in unit tests)."""

from emscatter.cli import main


def test_bench_lists_every_benchmark(capfd):
    assert main(["bench", "--list"]) == 0
    out = capfd.readouterr().out
    for name in ("kernels", "peers", "pareto", "scaling", "demo", "generate", "emissivity"):
        assert name in out


def test_bench_rejects_an_unknown_name(capfd):
    assert main(["bench", "fortran"]) == 2
    assert "unknown benchmark(s) ['fortran']" in capfd.readouterr().err
