"""MAVLink 2 signing keys.

A key file holds either 64 hexadecimal digits (the 32-byte secret key itself) or a
passphrase, whose SHA-256 is the key: MAVProxy's ``signing setup PASSPHRASE`` derives the
key the same way, so a vehicle set up from MAVProxy and this tool agree. The link layer
signs everything it sends with the key (pymavlink's ``setup_signing``); a vehicle that
requires signing ignores anything unsigned or signed with another key.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

from ..errors import FtlboError


class SigningKeyError(FtlboError):
    """A signing key file is missing or empty."""

    bad_input = True


def key_from_text(text: str) -> bytes:
    """Key file text -> 32-byte secret key (hex digits as-is, else SHA-256 of the passphrase)."""
    text = text.strip()
    if not text:
        raise ValueError("empty signing key")
    if re.fullmatch(r"[0-9a-fA-F]{64}", text):
        return bytes.fromhex(text)
    return hashlib.sha256(text.encode("utf-8")).digest()


def load_key(path: str | Path) -> bytes:
    from ..inputs import read_user_text

    path = Path(path)
    text = read_user_text(path, limit_bytes=1 << 20, error=lambda problem: SigningKeyError(
        f"{path}: cannot read the signing key: {problem}"))
    try:
        return key_from_text(text)
    except ValueError:
        raise SigningKeyError(f"{path}: the signing key file is empty") from None
