"""Paste a command's output into a Markdown file between ``<!-- NAME:begin -->`` and ``<!-- NAME:end -->`` (appended
at the end when the file has no such block), so every number in docs/ names the committed command that made it."""

from __future__ import annotations

import re
import time
from pathlib import Path


def paste(doc: Path, name: str, command: str, text: str, fenced: bool = True) -> None:
    body = f"```\n{text.strip()}\n```" if fenced else text.strip()
    block = f"<!-- {name}:begin -->\n`{command}` ({time.strftime('%Y-%m-%d')}):\n\n{body}\n<!-- {name}:end -->"
    pattern = rf"<!-- {re.escape(name)}:begin -->.*?<!-- {re.escape(name)}:end -->"
    old = Path(doc).read_text()
    new = re.sub(pattern, lambda _: block, old, flags=re.S) if re.search(pattern, old, re.S) else f"{old}\n{block}\n"
    Path(doc).write_text(new)
