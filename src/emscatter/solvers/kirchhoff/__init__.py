"""Kirchhoff approximation: geometric optics (stationary phase, with shadowing) and physical
optics (the scalar series), their shared geometry, Fresnel and coherent terms, and their
compiled kernels.

======================  ===============================================================
module                  what it holds
======================  ===============================================================
:mod:`.go`              GO solver (the registry's ``"go"``): ``bistatic``, ``check_validity``
:mod:`.go_backscatter`  GO backscatter in closed form (``backscatter()`` takes it)
:mod:`.transmission`     GO transmission (rough-dielectric BTDF, Walter et al. 2007)
:mod:`.po`              PO solver (the registry's ``"po"``), the log-space series
:mod:`.po_map`          PO on a height map itself (``po_map``): grating orders by FFT
:mod:`.common`          geometry, local Fresnel, Smith shadowing, Kirchhoff coherent part
:mod:`.compiled`        when the compiled kernels run; :mod:`.go_kernel`, :mod:`.po_kernel`
======================  ===============================================================
"""
