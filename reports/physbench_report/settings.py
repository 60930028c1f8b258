"""Engine settings: every setting an adapter changes from its engine's defaults, as metadata.json
carries each engine's settings table."""
from __future__ import annotations


def engine_settings(meta: dict) -> list[dict]:
    """Per engine its version and, per variant, the settings rows (name, value, why)."""
    engines = []
    for name, info in meta.get("engines", {}).items():
        info = info or {}  # older runs wrote null for an engine that only had unsupported rows
        variants = [dict(name=v, settings=s) for v, s in info.get("variants", {}).items()]
        engines.append(dict(name=name, version=info.get("version", ""), variants=variants))
    return engines
