import mitsuba as mi

from emscatter.brdf.export_npz import read_npz
from emscatter.brdf.export_rgl import write_rgl
from emscatter.render import mitsuba as em_mi

t = read_npz("gold.npz")  # or the table just built
mi.set_variant("llvm_ad_spectral")  # or llvm_ad_rgb, llvm_ad_mono
gold = {"type": "emscatter", "table": em_mi.register_table(t)}  # registers the plugin too
bsdf = mi.load_dict(em_mi.bsdf_dict(t, coherent=False))  # the same, with the plugin's options
scene = mi.load_dict(
    {
        "type": "scene",
        "integrator": {"type": "path"},
        "sensor": {
            "type": "perspective",
            "fov": 30,
            "to_world": mi.ScalarTransform4f().look_at([0, 0, 4], [0, 0, 0], [0, 1, 0]),
            "film": {"type": "hdrfilm", "width": 64, "height": 64},
        },
        "sphere": {"type": "sphere", "bsdf": gold},
        "sky": {"type": "constant"},
        "sun": {"type": "directional", "direction": [1, -1, -1], "irradiance": 3.0},
    }
)
image = mi.render(scene, spp=16)  # (64, 64, 3) linear RGB
mi.util.write_bitmap("gold.exr", image)
em_mi.register_table(t, "gold")  # XML names a table by its key
xml_bsdf = mi.load_string(
    '<bsdf version="3.0.0" type="emscatter"><string name="table" value="gold"/></bsdf>'
)
write_rgl("gold.bsdf", t, channels="spectral")  # for Mitsuba's own `measured` plugin
measured = mi.load_dict({"type": "measured", "filename": "gold.bsdf"})
