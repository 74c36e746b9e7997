"""Compatibility module: documents saved by machsurf 0.1 name their feature proxies
``freecad.machsurf.features.<Class>``; the features now live in :mod:`freecad.machsurf.app.features`."""

from .app.features import EffectiveRadiusFeature, EnvelopeFeature, FlankSettingFeature, MachiningSurfaceFeature, make  # noqa: F401
