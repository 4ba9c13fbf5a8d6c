"""Render adapters: one per thing drawn, each owning its pyvista actors."""
