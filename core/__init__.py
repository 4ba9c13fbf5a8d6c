"""bladecam core: planning for double-sided collaborative machining of propeller blades.

Pure numpy/scipy/trimesh; never imports Qt or VTK.
"""
__version__ = "0.1.0"
