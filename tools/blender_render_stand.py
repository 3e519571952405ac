# Renders a stand export of `sylva export` in Blender as an artist would first look at it: a
# perspective view from the south (the camera DIST metres south of the export area's centre and
# HEIGHT metres above the ground under it, looking north and slightly down), a sun behind the camera and a sky-blue
# world, Cycles on the
# CPU without denoising (Debian's Blender 3.4 is built without OpenImageDenoise).
#
#   xvfb-run -a blender -b --factory-startup --python tools/blender_render_stand.py -- \
#       STAND.glb OUT.png [--dist 40] [--height 14] [--pitch 82] [--lens 24] [--size 640x360] [--samples 16] \
#       [--sun 2.5] [--sky 0.8] [--exposure 0]
#
# --pitch is the camera's tilt from straight down in degrees (90: level, as a person looks;
# 82: slightly down, the default oblique view). An eye-height view from inside the stand's
# southern edge: --dist 8 --height 1.7 --pitch 95 --lens 18. The height is measured from the
# export's terrain under the camera (trial 37: measured from the export's origin, the patch's
# lowest point, the eye-height camera stood under the ground of a slope); where no terrain is
# under the camera, from the highest terrain on its line to the area's centre (trial 47 D3).
#
# Blender 3.4 with numpy 1.24: the glTF importer needs `np.bool`.
import math
import sys

import bpy
import numpy as np
from mathutils import Vector

if not hasattr(np, "bool"):
    np.bool = bool  # the glTF importer of Blender 3.4 still uses the alias numpy 1.24 removed

argv = sys.argv[sys.argv.index("--") + 1:]
glb, png = argv[0], argv[1]
opts = dict(zip(argv[2::2], argv[3::2]))
dist = float(opts.get("--dist", "40"))
height = float(opts.get("--height", "14"))
w, h = (int(v) for v in opts.get("--size", "640x360").split("x"))
samples = int(opts.get("--samples", "16"))
pitch = float(opts.get("--pitch", "82"))
lens = float(opts.get("--lens", "24"))
# light: the sun's strength (W/m²) and the sky's; with Blender's default Filmic view the
# earlier 4 and 1.5 washed out mid-grey bark (beech, sRGB 150) to white (round 34)
sun_energy = float(opts.get("--sun", "2.5"))
sky = float(opts.get("--sky", "0.8"))
exposure = float(opts.get("--exposure", "0"))

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
scene = bpy.context.scene
cam_data = bpy.data.cameras.new("cam")
cam_data.lens = lens
cam_data.clip_start = 0.05
cam = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(cam)


def ground_under(x, y):
    """Elevation (scene z) of the export's terrain mesh under (x, y), or None where there is
    none: a ray cast straight down on the `terrain` object only (not the trees)."""
    for o in scene.objects:
        if o.type != "MESH" or not o.name.startswith("terrain"):
            continue
        inv = o.matrix_world.inverted()
        top, bottom = inv @ Vector((x, y, 1.0e5)), inv @ Vector((x, y, -1.0e5))
        hit, loc, _normal, _face = o.ray_cast(top, (bottom - top).normalized())
        if hit:
            return (o.matrix_world @ loc).z
    return None


def camera_ground(x, y):
    """The ground the camera's height is measured from: the terrain under it; where none is
    (a camera outside the exported patch), the highest terrain on the line from it to the
    area's centre, so that the camera looks over the patch rather than at its underside from
    below (trial 47 D3: a 36 % slope's patch seen from under its edge); 0 without terrain."""
    g = ground_under(x, y)
    if g is not None:
        return g
    hits = [ground_under(x * (1.0 - k / 64.0), y * (1.0 - k / 64.0)) for k in range(65)]
    hits = [h for h in hits if h is not None]
    return max(hits) if hits else 0.0


# the glTF's y-up scene comes in z-up, the export area's centre at the origin
cam.location = (0.0, -dist, camera_ground(0.0, -dist) + height)
cam.rotation_euler = (math.radians(pitch), 0.0, 0.0)
scene.camera = cam
sun = bpy.data.lights.new("sun", "SUN")
sun.energy = sun_energy
sun_obj = bpy.data.objects.new("sun", sun)
# from the south-east behind the camera, 55 degrees up: the camera sees the lit side of the
# crowns (the leaf material is opaque: a card lit from behind reads dark)
sun_obj.rotation_euler = (math.radians(35), 0.0, math.radians(25))
scene.collection.objects.link(sun_obj)
world = bpy.data.worlds.new("sky")
scene.world = world
world.use_nodes = True
world.node_tree.nodes["Background"].inputs[0].default_value = (0.55, 0.7, 0.9, 1.0)
world.node_tree.nodes["Background"].inputs[1].default_value = sky
scene.view_settings.exposure = exposure
scene.render.engine = "CYCLES"
scene.cycles.samples = samples
scene.cycles.device = "CPU"
scene.cycles.use_denoising = False
scene.render.resolution_x = w
scene.render.resolution_y = h
scene.render.resolution_percentage = 100
scene.render.filepath = png
bpy.ops.render.render(write_still=True)
