"""Rendering with Mitsuba 3: an emscatter BRDF table as a BSDF, scenes of sphere rows, a demo.

Mitsuba is imported lazily (only :mod:`.mitsuba`, :mod:`.scenes` and :mod:`.demo` need it).

* :mod:`.mitsuba` — the ``"emscatter"`` BSDF plugin: :func:`~.mitsuba.bsdf_dict`,
  :func:`~.mitsuba.register_table`, :func:`~.mitsuba.register`;
* :mod:`.plugin_data` — what the plugin looks up, prepared in numpy;
* :mod:`.scenes` — rows of spheres, camera, lights, environment;
* :mod:`.demo` — the quick export + render the main demo runs.
"""
