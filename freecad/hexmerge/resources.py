# SPDX-License-Identifier: LGPL-2.1-or-later
"""Where the add-on's files outside the Python package live: icons and .ui files under the
repository's (or the installed Mod folder's) resources/."""

import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def resource_path(*parts):
    """Path of a file under resources/, e.g. resource_path("icons", "X.svg")."""
    return os.path.join(ROOT, "resources", *parts)
