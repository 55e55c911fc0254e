"""Rendering motions: 3D stick figures as GIF, MP4 and PNG contact sheets."""
from satagraph.viz.render import (contacts, frame_count, render,
                                  render_frames, save_gif, save_mp4,
                                  save_sheet)

__all__ = ["render", "render_frames", "frame_count", "contacts", "save_gif",
           "save_mp4", "save_sheet"]
