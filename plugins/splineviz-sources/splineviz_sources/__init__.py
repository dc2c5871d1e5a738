"""The "Sources" plugin: thesis test functions as synthetic volumes.

Registered through the ``splineviz.plugins`` entry point; the functions come from
:data:`splineviz.core.testfunctions.TEST_FUNCTIONS` (thesis §5.5 blob, Franke, Marschner-Lobb;
§5.6 Barth's sextic; Fig. 6.20 Chmutov), sampled on their usual domain.
"""

from __future__ import annotations

#: source name -> (TEST_FUNCTIONS key, menu title, default grid)
SOURCES = {
    "marschner-lobb": ("ml", "Marschner-Lobb", (41, 41, 41)),
    "barth": ("barth", "Barth's sextic", (64, 64, 64)),
    "chmutov": ("chmutov", "Chmutov surface", (64, 64, 64)),
    "blob": ("blob", "Blob", (32, 32, 32)),
    "franke": ("fr", "Franke (3-D)", (32, 32, 32)),
}


def register(api) -> None:
    """Entry point: add every source to the :class:`splineviz.plugins.PluginAPI`."""
    from splineviz.core.testfunctions import TEST_FUNCTIONS

    for name, (key, title, shape) in SOURCES.items():
        f = TEST_FUNCTIONS[key]
        api.add_source(name, f, f.domain, title=title, shape=shape, isovalue=f.isovalue,
                       description=f.description)
