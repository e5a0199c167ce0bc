"""The main loop the radio worker scripts share (tests/radio_worker.py, radio_xpd_worker.py,
radio_transmission_worker.py): run the named checks, record each one's result or traceback and
the emscatter warnings it raised, print one JSON line (the calling test reads the last line)."""

from __future__ import annotations

import json
import traceback
import warnings


def run_checks(checks: dict, argv) -> int:
    results = {}
    for name in argv:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                results[name] = {"result": checks[name]()}
            except Exception:  # the test shows the traceback
                results[name] = {"error": traceback.format_exc()}
        results[name]["warnings"] = [
            f"{w.category.__name__}: {w.message}"
            for w in caught
            if w.category.__module__.startswith("emscatter") or "emscatter" in str(w.filename)
        ]
    print(json.dumps(results, default=str))
    return 0
