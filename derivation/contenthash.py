"""The content hash in the header of every generated module (hashlib only, no sympy).

``codegen.module_text`` writes it; the runtime checks it when it loads a user's curve
module, and ``billiard derive --check`` names a file whose hash no longer matches.
"""

from __future__ import annotations

import hashlib

HASH_PREFIX = "# content sha256: "


def content_hash(body: str) -> str:
    return hashlib.sha256(body.encode()).hexdigest()


def split_module(text: str) -> tuple[str, str]:
    """Return (recorded hash, body) of a generated module; ('', text) if it has none."""
    head, sep, rest = text.partition(HASH_PREFIX)
    if not sep:
        return "", text
    digest, _, body = rest.partition("\n")
    return digest.strip(), body


def hash_matches(text: str) -> bool:
    """True if the module text carries a content hash and its body still matches it."""
    digest, body = split_module(text)
    return bool(digest) and content_hash(body) == digest
