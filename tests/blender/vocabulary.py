"""The rule of tests/test_vocabulary.py, for the Blender suite (its own venv and rootdir)."""
import re

COUNT = re.compile(r"(\w+)\s+samples per (pixel|pass)", re.IGNORECASE)


def unqualified_counts(text: str) -> list[str]:
    """The phrases of `text` that count samples per pixel or per pass without saying camera."""
    return [m.group(0) for m in COUNT.finditer(text or "") if m.group(1).lower() != "camera"]
