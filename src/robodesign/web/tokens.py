"""Withdrawal tokens: chosen or random, stored only as salted PBKDF2 hashes."""
from __future__ import annotations

import hashlib
import hmac
import secrets
from typing import Optional

from robodesign.core.errors import InputError

_ITERATIONS = 20_000


def hash_token(token: str) -> str:
    salt = secrets.token_bytes(16)
    h = hashlib.pbkdf2_hmac("sha256", token.encode(), salt, _ITERATIONS)
    return f"pbkdf2_sha256${_ITERATIONS}${salt.hex()}${h.hex()}"


def verify_token(token: Optional[str], stored: str) -> bool:
    if not token:
        return False
    try:
        algo, it, salt, h = stored.split("$")
        if algo != "pbkdf2_sha256":
            return False
        got = hashlib.pbkdf2_hmac("sha256", token.encode(), bytes.fromhex(salt), int(it))
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(got.hex(), h)


def check_token(token: str) -> str:
    """A token chosen by the uploader: 8 to 200 characters, no NUL (else InputError)."""
    if not (8 <= len(token) <= 200):
        raise InputError("a chosen token must have 8 to 200 characters (or leave it empty to get a random one)")
    if "\x00" in token:
        raise InputError("the token contains a NUL character")
    return token
