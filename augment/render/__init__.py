"""Rendering into the photo: furniture meshes, the GL context, lighting and shadows,
the board erased, and each suggestion as a glTF scene."""
