"""bladecam workbench: the Qt GUI on top of the planning package ``core``."""
