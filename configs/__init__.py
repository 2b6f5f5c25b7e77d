"""Strict YAML loading of frozen-dataclass configurations.

Every tunable number of the project lives in a frozen dataclass whose defaults are documented
(with units) and whose values can be loaded from a YAML file in this folder. Loading is strict:
an unknown key, a key written twice in one mapping, a missing required key or a value of the
wrong type (a string for a number, a number for a true/false, a non-finite number) raises
`ConfigError` naming the key, the file and what is allowed. `check_field_types` applies the
same type rules to a dataclass built directly in Python (call it from ``__post_init__``).

Typical use::

    from configs import load_config
    tol = load_config(Tolerances, "qshape")            # configs/qshape.yaml
    tol = load_config(Tolerances, "qshape", color_distance=0.3)   # keyword overrides
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import numbers
import types
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

import yaml

CONFIG_DIR = Path(__file__).resolve().parent
"""Folder holding the bundled YAML configurations."""

T = TypeVar("T")


class ConfigError(ValueError):
    """A configuration file or override is malformed (unknown key, wrong type, missing file)."""


class _DuplicateKey(yaml.YAMLError):
    """A mapping of a YAML document has the same key twice (the loader refuses it)."""


class _StrictLoader(yaml.SafeLoader):
    """`yaml.SafeLoader` that refuses duplicate keys instead of keeping the last one."""


def _strict_mapping(loader: _StrictLoader, node: yaml.MappingNode, deep: bool = False) -> Any:
    first_line: dict[Any, int] = {}
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":
            continue  # `<<: *anchor` merges are allowed to be overridden
        key = loader.construct_object(key_node, deep=True)
        line = key_node.start_mark.line + 1
        try:
            earlier = first_line.get(key)
        except TypeError:
            raise _DuplicateKey(f"line {line}: a mapping key must be a plain value") from None
        if earlier is not None:
            raise _DuplicateKey(
                f"line {line}: duplicate key {key!r} (first at line {earlier}); each key may "
                "appear once per mapping"
            )
        first_line[key] = line
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _strict_mapping)


PARSED_TEXTS = 256
"""YAML texts whose parse is remembered (`parse_yaml`), least recently used dropped first: a
configuration file of a few kB each, well under a MB in all."""


def parse_yaml(text: str) -> Any:
    """Parse YAML text safely, refusing duplicate keys.

    The same text is parsed once (the last `PARSED_TEXTS` texts are remembered): every env
    build reads the same configuration files again, and PyYAML's pure-Python parser cost more
    than the rest of building some envs. Each call returns a fresh copy.

    Raises:
        yaml.YAMLError: Malformed YAML or a duplicate key (the message names it and its lines).
    """
    return copy.deepcopy(_parse_once(text))


@functools.lru_cache(maxsize=PARSED_TEXTS)
def _parse_once(text: str) -> Any:
    return yaml.load(text, Loader=_StrictLoader)  # noqa: S506 (a SafeLoader subclass)


def resolve_path(name_or_path: str | Path, subdir: str = "") -> Path:
    """Find a YAML file by bundled name (``"qshape"``) or by path.

    Args:
        name_or_path: A path to an existing file, or the stem of a file in
            ``configs/<subdir>/`` (``.yaml`` is appended).
        subdir: Sub-folder of ``configs/`` searched for bundled names.

    Raises:
        ConfigError: Neither a file nor a bundled name (the message lists the bundled names),
            or not a string or path at all.
    """
    if not isinstance(name_or_path, str | Path):
        raise ConfigError(
            f"a configuration is named by a bundled name or a file path (str or Path), got "
            f"{type(name_or_path).__name__}"
        )
    path = Path(name_or_path)
    if path.is_file():
        return path
    folder = CONFIG_DIR / subdir
    bundled = folder / f"{name_or_path}.yaml"
    if bundled.is_file():
        return bundled
    names = sorted(p.stem for p in folder.glob("*.yaml"))
    raise ConfigError(
        f"no configuration file {str(name_or_path)!r}: not a file, and not a bundled name in "
        f"{folder} (bundled: {', '.join(names) or 'none'})"
    )


def load_yaml(name_or_path: str | Path, subdir: str = "") -> dict[str, Any]:
    """Read a YAML mapping from a bundled name or a path.

    Raises:
        ConfigError: The file is missing, unreadable, not YAML, has a duplicate key, or is not
            a mapping at top level.
    """
    path = resolve_path(name_or_path, subdir)
    try:
        data = parse_yaml(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ConfigError(f"cannot read configuration {path}: {exc}") from exc
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: top level must be a mapping of keys, got {type(data).__name__}")
    return data


def _convert(value: Any, hint: Any, where: str) -> Any:
    """Convert a YAML value to the annotated type, strictly."""
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if hint is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _convert(value, arg, where)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(f"{where}: {value!r} fits none of {hint}: {'; '.join(errors)}")
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(f"{where}: {value!r} is not allowed; allowed: {list(args)}")
        return value
    if dataclasses.is_dataclass(hint) and isinstance(hint, type):
        if isinstance(value, hint):
            return value
        if not isinstance(value, Mapping):
            raise ConfigError(f"{where}: expected a mapping for {hint.__name__}, got {value!r}")
        return from_dict(hint, value, source=where)
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise ConfigError(f"{where}: expected a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], f"{where}[{i}]") for i, v in enumerate(value))
        if len(args) != len(value):
            raise ConfigError(f"{where}: expected {len(args)} values, got {len(value)}")
        pairs = enumerate(zip(args, value, strict=True))
        return tuple(_convert(v, a, f"{where}[{i}]") for i, (a, v) in pairs)
    if origin in (dict, Mapping):
        if not isinstance(value, Mapping):
            raise ConfigError(f"{where}: expected a mapping, got {value!r}")
        return {
            _convert(k, args[0], where): _convert(v, args[1], f"{where}.{k}")
            for k, v in value.items()
        }
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: expected true/false, got {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ConfigError(f"{where}: expected a number, got {value!r}")
        if not math.isfinite(value):
            raise ConfigError(f"{where}: expected a finite number, got {value!r}")
        return float(value)
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise ConfigError(f"{where}: expected an integer, got {value!r}")
        return int(value)
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where}: expected a string, got {value!r}")
        return value
    return value


def from_dict(cls: type[T], data: Mapping[str, Any], *, source: str = "<dict>") -> T:
    """Build the frozen dataclass ``cls`` from a mapping, strictly.

    Nested dataclass fields accept nested mappings. Tuples accept YAML lists.

    Raises:
        ConfigError: Unknown key (the message lists the allowed ones), missing required key,
            or a value of the wrong type.
    """
    if not (dataclasses.is_dataclass(cls) and isinstance(cls, type)):
        raise TypeError(f"{cls!r} is not a dataclass type")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(
            f"{source}: unknown key(s) {unknown} for {cls.__name__}; allowed: {sorted(fields)}"
        )
    hints = typing.get_type_hints(cls)
    kwargs = {k: _convert(v, hints[k], f"{source}.{k}") for k, v in data.items()}
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise ConfigError(f"{source}: {exc}") from exc


def check_field_types(obj: object) -> None:
    """Apply `from_dict`'s type rules to a dataclass instance built directly (``__post_init__``).

    bool fields must hold bools, number fields finite numbers (ints are widened to float),
    tuple fields sequences of the right element type (lists become tuples), Literal fields one
    of their values. Converted values are written back into the (frozen) instance.

    Raises:
        ConfigError: A field of the wrong type; the message names the class, field and value.
    """
    if not dataclasses.is_dataclass(obj) or isinstance(obj, type):
        raise TypeError(f"{obj!r} is not a dataclass instance")
    cls = type(obj)
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(obj):
        if not f.init:
            continue
        value = getattr(obj, f.name)
        converted = _convert(value, hints[f.name], f"{cls.__name__}.{f.name}")
        if converted is not value:
            object.__setattr__(obj, f.name, converted)


def load_config(
    cls: type[T], name_or_path: str | Path | None = None, subdir: str = "", **overrides: Any
) -> T:
    """Load ``cls`` from YAML (bundled name or path), then apply keyword overrides.

    Args:
        cls: A frozen dataclass type.
        name_or_path: Bundled name or path of a YAML file; None uses the dataclass defaults.
        subdir: Sub-folder of ``configs/`` for bundled names.
        **overrides: Top-level keys replacing the file's values (validated the same way).

    Raises:
        ConfigError: See `from_dict`.
    """
    data: dict[str, Any] = {}
    source = "<defaults>"
    if name_or_path is not None:
        data = load_yaml(name_or_path, subdir)
        source = str(resolve_path(name_or_path, subdir))
    data.update(overrides)
    return from_dict(cls, data, source=source)


__all__ = [
    "CONFIG_DIR",
    "PARSED_TEXTS",
    "ConfigError",
    "check_field_types",
    "from_dict",
    "load_config",
    "load_yaml",
    "parse_yaml",
    "resolve_path",
]
