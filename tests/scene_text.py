"""Scene-file text shared by tests that write small scenes: a camera, a tiny film and a grey diffuse material, to
which a test appends its shapes and settings."""

CAMERA_FILM_GREY = """
[camera]
origin = [0, 0, 5]
target = [0, 0, 0]
fov = 40

[film]
width = 8
height = 6

[materials.grey]
type = "diffuse"
reflectance = { value = 0.5 }
"""
