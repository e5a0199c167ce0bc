import os
import sys

# Shared test helpers (tests/laws.py) importable as `laws`.
sys.path.insert(0, os.path.dirname(__file__))
# Headless plotting everywhere.
os.environ.setdefault("MPLBACKEND", "Agg")
# The on-disk result cache (emscatter.cache) is off in tests unless a test turns it on with its
# own EMSCATTER_CACHE_DIR: results and evaluation counts must come from this run's code.
os.environ.setdefault("EMSCATTER_CACHE", "0")

import shutil  # noqa: E402
import tempfile  # noqa: E402

import pytest  # noqa: E402

#: Prefixes of what emscatter, its demo and its tests create in the temp dir.
TEMP_PREFIXES = ("emscatter-", "radio-xml-")

# Each test process (the pytest-xdist controller and every worker) gets a private temp dir,
# inherited by the subprocesses it starts (TMPDIR): what the session finds there at the end was
# left by this session's code, not by another worker or another program sharing /tmp.
_SYSTEM_TMP = tempfile.gettempdir()
_SESSION_TMP = tempfile.mkdtemp(prefix="pytest-session-tmp-", dir=_SYSTEM_TMP)
os.environ["TMPDIR"] = _SESSION_TMP
tempfile.tempdir = _SESSION_TMP


def pytest_unconfigure(config):
    shutil.rmtree(_SESSION_TMP, ignore_errors=True)


def _temp_entries() -> set[str]:
    try:
        names = os.listdir(tempfile.gettempdir())
    except OSError:
        return set()
    return {n for n in names if n.startswith(TEMP_PREFIXES)}


@pytest.fixture(scope="session", autouse=True)
def nothing_left_in_the_temp_dir():
    """Fails the session if entries with emscatter's prefixes (:data:`TEMP_PREFIXES`) were
    added to the temp dir (``tempfile.gettempdir()``, private to this process — see above)
    between its start and its end. Only those names are compared, so pytest's own folders and
    other libraries' files do not count."""
    before = _temp_entries()
    yield
    added = sorted(_temp_entries() - before)
    if added:
        pytest.fail(
            f"left in the temp dir by this test session: {added} (remove temporary files and "
            "folders once used, e.g. with tempfile.TemporaryDirectory)",
            pytrace=False,
        )


# Hypothesis profiles (issue 23), chosen once for every test module:
# * "dev" (the default on a laptop): fresh random examples on every run, and the failures it
#   finds kept in the local example database (.hypothesis/ at the repository root) and
#   replayed first on the next runs until they pass;
# * "ci" (the default where CI is set, as on every CI service): derandomized — the same
#   examples for the same code — and no database, so a run depends on the commit only;
# * "long" (HYPOTHESIS_PROFILE=long): the dev profile with 20× the examples (test_properties).
# A failure found either way becomes an explicit @example in the test (a regression that
# every profile runs), never a narrower strategy.
try:
    from hypothesis import HealthCheck, settings
    from hypothesis.database import DirectoryBasedExampleDatabase
except ImportError:  # the suite's hypothesis tests importorskip it
    pass
else:
    _COMMON = dict(
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
        print_blob=True,
    )
    _DB = DirectoryBasedExampleDatabase(
        os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), ".hypothesis")
    )
    settings.register_profile("ci", derandomize=True, database=None, **_COMMON)
    settings.register_profile("dev", derandomize=False, database=_DB, **_COMMON)
    settings.register_profile("long", derandomize=False, database=_DB, **_COMMON)
    _CI = os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if _CI else "dev"))
