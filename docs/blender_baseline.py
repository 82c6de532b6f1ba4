# The path tracer vkray's whole-render time is compared with (docs/speed.md): Blender's
# Cycles writing the same depth and normal passes of an OBJ model, from the camera `vkray render
# MODEL.obj` frames it with, 1 sample on the CPU, to a multilayer OpenEXR, at Blender's fastest:
# its C++ OBJ importer (wm.obj_import, Blender 3.2 and later; the legacy Python one took 0.6 s more
# on the bunny), no light bounces (a ray's first hit is all the passes hold), no adaptive sampling.
#
#   blender -b --factory-startup -noaudio -P docs/blender_baseline.py -- MODEL.obj OUT.exr WIDTH HEIGHT [VIEWS]
#
# With VIEWS, it renders that many views in one process, as `vkray render MODEL.obj --orbit VIEWS`
# does: view k turned about +y through the centre by 360 k / VIEWS degrees (counterclockwise seen
# from above), each to OUT with "#####" standing for k zero-padded (out/view-#####.exr). Cycles
# keeps its scene between them (persistent data): Blender's fastest way to render many views.
#
# The framing repeats engine/scene/framing.cpp: the centre of the vertices' bounding box, the radius of
# the farthest vertex from it, seen from the direction (0, 0.25, 1), up +y, 40 degrees across the
# shorter side, at the distance where that sphere touches the shorter borders. The model keeps its
# own coordinates (the importer's axes set to Blender's own), so the camera is vkray's.
import math
import sys

import bpy
from mathutils import Matrix, Vector

arguments = sys.argv[sys.argv.index("--") + 1:]
model, output, width, height = arguments[:4]
width, height = int(width), int(height)
views = int(arguments[4]) if len(arguments) > 4 else 0

positions = []
with open(model) as obj:
    for line in obj:
        if line.startswith("v "):
            positions.append(Vector([float(value) for value in line.split()[1:4]]))
lower = Vector([min(p[k] for p in positions) for k in range(3)])
upper = Vector([max(p[k] for p in positions) for k in range(3)])
centre = (lower + upper) / 2
radius = max((p - centre).length for p in positions)
fovy = math.radians(40.0)
half = fovy / 2 if width >= height else math.atan(math.tan(fovy / 2) * width / height)
eye = centre + radius / math.sin(half) * Vector((0.0, 0.25, 1.0)).normalized()

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=model, forward_axis="Y", up_axis="Z")

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
bpy.context.scene.collection.objects.link(camera)


def aim(eye):
    forward = (centre - eye).normalized()
    right = forward.cross(Vector((0.0, 1.0, 0.0))).normalized()
    up = right.cross(forward)
    # A Blender camera looks down its local -z with its local +y up.
    camera.matrix_world = Matrix.Translation(eye) @ Matrix((right, up, -forward)).transposed().to_4x4()


aim(eye)
camera.data.sensor_fit = "VERTICAL" if width >= height else "HORIZONTAL"
camera.data.angle = 2 * half
camera.data.clip_end = 10 * (eye - centre).length

scene = bpy.context.scene
scene.camera = camera
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 1
scene.cycles.use_adaptive_sampling = False
scene.cycles.max_bounces = 0
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = width, height
scene.render.resolution_percentage = 100
layer = scene.view_layers[0]
layer.use_pass_z = True
layer.use_pass_normal = True
settings = scene.render.image_settings
settings.file_format = "OPEN_EXR_MULTILAYER"
settings.color_depth = "32"
settings.exr_codec = "ZIP"
if not views:
    scene.render.filepath = output
    bpy.ops.render.render(write_still=True)
else:
    scene.render.use_persistent_data = True
    for k in range(views):
        angle = 2 * math.pi * k / views
        offset = eye - centre
        turned = Vector((offset.x * math.cos(angle) + offset.z * math.sin(angle), offset.y,
                         -offset.x * math.sin(angle) + offset.z * math.cos(angle)))
        aim(centre + turned)
        scene.render.filepath = output.replace("#####", "%05d" % k)
        bpy.ops.render.render(write_still=True)
