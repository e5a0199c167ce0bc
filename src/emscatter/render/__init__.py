"""Rendering with Mitsuba 3: an emscatter BRDF table as a BSDF, scenes of sphere rows, a demo.

Mitsuba is imported lazily: ``import emscatter.render`` needs nothing beyond numpy.

* :mod:`.mitsuba` — the ``"emscatter"`` BSDF plugin: :func:`~.mitsuba.bsdf_dict`,
  :func:`~.mitsuba.register_table`, :func:`~.mitsuba.register`;
* :mod:`.plugin_data` — what the plugin looks up, prepared in numpy once per table;
* :mod:`.sampling` — the marginal/conditional alias tables it importance-samples from;
* :mod:`.scenes` — rows of spheres, a procedural sky, rendering and tone-mapped figures;
* :mod:`.demo` — the demo's quick RGL export + spectral render (run in its own process);
* :mod:`.cli_options` — the options of the scripts in ``examples/render/``.

The RGL ``.bsdf`` export for Mitsuba's own ``measured`` plugin is
:mod:`emscatter.brdf.export_rgl`.
"""
