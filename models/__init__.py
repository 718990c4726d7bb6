"""MJCF models of the vrig test rigs (data package; see README.md)."""
