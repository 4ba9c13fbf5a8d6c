"""bladecam core: planning for double-sided collaborative machining of propeller blades.

Pure numpy/scipy/trimesh; never imports Qt or VTK. Sub-packages follow the paper: blade (the blade
model and its sources), paths (sections 2-4), schedule (section 5), machine (the XYZ-3RPS machines),
output (the plan folder); records holds the plain records they share, planner chains the stages.
"""

__version__ = "0.1.0"
