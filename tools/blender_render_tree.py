# Renders one tree written by `sylva tree grow` / `sylva tree adapt` (a .glb) in Blender from
# several cameras in one session (the file is imported once): for close looks at a hero tree's
# leaves, bark and root flare. Cycles on the CPU without denoising (Debian's Blender 3.4 is
# built without OpenImageDenoise); a sun from the south-east, 50 degrees up, and a sky-blue
# world, as tools/blender_render_stand.py lights a stand.
#
#   xvfb-run -a blender -b --factory-startup --python tools/blender_render_tree.py -- \
#       TREE.glb OUT_PREFIX NAME:EX,EY,EZ:TX,TY,TZ:LENS [...] [--size 640x480] [--samples 16]
#
# Each view NAME is written to OUT_PREFIX_NAME.png, seen from the eye (EX, EY, EZ) towards the
# target (TX, TY, TZ) with a lens of LENS mm (36 mm film). Coordinates in metres in Sylva's
# frame (x east, y north, z up, the stem base at the origin), which is Blender's once the
# importer has turned the glTF's y-up scene z-up.
import math
import sys

import bpy
import numpy as np
from mathutils import Vector

if not hasattr(np, "bool"):
    np.bool = bool  # the glTF importer of Blender 3.4 still uses the alias numpy 1.24 removed

argv = sys.argv[sys.argv.index("--") + 1:]
glb, prefix = argv[0], argv[1]
views, opts, i = [], {}, 2
while i < len(argv):
    if argv[i].startswith("--"):
        opts[argv[i]] = argv[i + 1]
        i += 2
    else:
        views.append(argv[i])
        i += 1
w, h = (int(v) for v in opts.get("--size", "640x480").split("x"))
samples = int(opts.get("--samples", "16"))

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
scene = bpy.context.scene
meshes = [o for o in scene.objects if o.type == "MESH"]
print("imported", glb, "meshes", len(meshes), "triangles", sum(sum(len(p.vertices) - 2 for p in o.data.polygons) for o in meshes))
# a ground disc so that the flare stands on something
bpy.ops.mesh.primitive_circle_add(vertices=64, radius=40.0, fill_type="NGON", location=(0.0, 0.0, 0.0))
ground = bpy.context.active_object
mat = bpy.data.materials.new("ground")
mat.use_nodes = True
mat.node_tree.nodes["Principled BSDF"].inputs[0].default_value = (0.09, 0.075, 0.05, 1.0)
ground.data.materials.append(mat)
cam_data = bpy.data.cameras.new("cam")
cam_data.clip_start = 0.02
cam = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(cam)
scene.camera = cam
# the sun from the south-east, 50 degrees up, and a sky-blue world (as blender_render_stand.py)
sun_obj = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun_obj.data.energy, sun_obj.rotation_euler = 2.5, (math.radians(40), 0.0, math.radians(35))
scene.collection.objects.link(sun_obj)
scene.world = bpy.data.worlds.new("sky")
scene.world.use_nodes = True
background = scene.world.node_tree.nodes["Background"].inputs
background[0].default_value, background[1].default_value = (0.55, 0.7, 0.9, 1.0), 0.8
render = scene.render
render.engine, render.resolution_x, render.resolution_y, render.resolution_percentage = "CYCLES", w, h, 100
scene.cycles.samples, scene.cycles.device, scene.cycles.use_denoising = samples, "CPU", False
for v in views:
    name, eye, target, lens = v.split(":")
    eye = Vector([float(x) for x in eye.split(",")])
    target = Vector([float(x) for x in target.split(",")])
    cam_data.lens = float(lens)
    cam.location = eye
    cam.rotation_euler = (target - eye).to_track_quat("-Z", "Y").to_euler()
    scene.render.filepath = f"{prefix}_{name}.png"
    bpy.ops.render.render(write_still=True)
    print("wrote", scene.render.filepath)
