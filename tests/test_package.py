"""Package-level promises: a light import and a working tour."""

import subprocess
import sys


def test_import_is_light():
    code = (
        "import sys, emscatter; "
        "heavy = [m for m in ('mitsuba', 'drjit', 'sionna', 'dask', 'matplotlib', "
        "'scipy.integrate') if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_package_docstring_tour_runs():
    import emscatter

    src = emscatter.__doc__.split("::", 1)[1].split("See ``README.md``")[0]
    code = "\n".join(line[4:] for line in src.splitlines())
    exec(compile(code, "emscatter-tour", "exec"), {})
