"""Compatibility module: documents saved by machsurf 0.1 name their view providers
``freecad.machsurf.gui_view.ViewProvider``; they now live in :mod:`freecad.machsurf.gui.view`."""

from .gui.view import ViewProvider  # noqa: F401
