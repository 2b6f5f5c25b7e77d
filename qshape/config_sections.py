"""Loading one section of a qshape or vision YAML file strictly into a frozen dataclass.

``configs/qshape.yaml`` holds the ``tolerances``, ``outline`` and ``limits`` sections;
``configs/vision.yaml`` the ``design``, ``render``, ``extract`` and ``synth`` sections.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

from configs import ConfigError, from_dict, load_yaml, resolve_path

T = TypeVar("T")


def load_section(
    cls: type[T],
    section: str,
    name_or_path: str | Path | None,
    overrides: Mapping[str, Any],
    *,
    default: str = "vision",
) -> T:
    """Load one section of a YAML file strictly into ``cls``, then apply keyword overrides.

    Args:
        cls: A frozen dataclass type.
        section: Top-level key of the section.
        name_or_path: Bundled config name or YAML path; None: the bundled ``default``.
        overrides: Field values replacing the file's.
        default: Bundled file used when ``name_or_path`` is None (``"vision"``, ``"qshape"``).

    A file without the section but with other sections gives the dataclass defaults; a file
    with no sections at all (only keys at top level) is taken as the section itself.

    Raises:
        configs.ConfigError: Missing file, duplicate or unknown key, wrong type, or the section
            is not a mapping.
    """
    name = default if name_or_path is None else name_or_path
    data = load_yaml(name)
    source = str(resolve_path(name))
    if section in data:
        body = data[section]
        if not isinstance(body, dict):
            raise ConfigError(f"{source}: {section!r} must be a mapping")
    elif any(isinstance(v, dict) for v in data.values()):
        body = {}
    else:
        body = data
    return from_dict(cls, {**body, **overrides}, source=f"{source}:{section}")


__all__ = ["load_section"]
