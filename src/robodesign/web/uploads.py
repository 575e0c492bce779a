"""Reading requests: multipart and raw upload bodies (:func:`read_upload`, capped in files and fields),
text decoding, base64 file maps, query numbers; and the error answer (JSON for the API, a page otherwise)."""
from __future__ import annotations

import base64
import binascii
import math
from typing import Dict, List, Optional, Tuple

from fastapi import Request
from fastapi.responses import HTMLResponse, JSONResponse, Response
from starlette.datastructures import UploadFile

from robodesign.core.errors import InputError
from robodesign.web import pages
from robodesign.web.middleware import BodyTooLarge, BodyTooSlow
from robodesign.web.safefiles import TooLarge
from robodesign.web.site_settings import MiB

MAX_FORM_FILES = 256  # files in one multipart body (more: send a zip); the parser stops at the first one beyond
MAX_FORM_FIELDS = 32  # other fields of one form


def is_api(request: Request) -> bool:
    return request.url.path.startswith("/api/")


def error_response(request: Request, status: int, message: str) -> Response:
    bench = getattr(request.app.state, "bench", None)
    if bench is not None:  # never show the server's own paths
        message = message.replace(str(bench.data), "<data>")
    if is_api(request):
        return JSONResponse({"detail": message}, status_code=status)
    return HTMLResponse(pages.error_page(status, message), status_code=status)


def decode_text(raw: bytes, name: str) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise InputError(f"not UTF-8 text (byte {e.start})", file=name) from None


class Upload:
    """A parsed request body: form fields, uploaded files, or the raw body (JSON / zip)."""

    def __init__(self):
        self.fields: Dict[str, str] = {}
        self.files: Dict[str, List[Tuple[str, bytes]]] = {}
        self.raw: Optional[bytes] = None
        self.content_type = ""

    def file(self, *names) -> Optional[Tuple[str, bytes]]:
        for n in names:
            if self.files.get(n):
                return self.files[n][0]
        return None

    def field(self, name: str, request: Request) -> Optional[str]:
        v = self.fields.get(name)
        if v is None:
            v = request.query_params.get(name)
        return v


async def read_upload(request: Request) -> Upload:
    up = Upload()
    ct = request.headers.get("content-type", "").split(";")[0].strip().lower()
    up.content_type = ct
    if ct in ("multipart/form-data", "application/x-www-form-urlencoded"):
        try:
            form = await request.form(max_files=MAX_FORM_FILES, max_fields=MAX_FORM_FIELDS, max_part_size=4 * MiB)
        except (BodyTooLarge, BodyTooSlow):
            raise
        except Exception as e:  # malformed multipart body, or too many parts (stopped at the first beyond)
            if "Too many" in str(e):
                raise TooLarge(f"{str(e).removeprefix('400: ')} (send many files as one zip)") from None
            raise InputError(f"malformed form data ({e})") from None
        for key, value in form.multi_items():
            if isinstance(value, UploadFile):
                data = await value.read()
                up.files.setdefault(key, []).append((value.filename or key, data))
            else:
                up.fields[key] = str(value)
    else:
        up.raw = await request.body()
    return up


def is_zip(name: str, data: bytes) -> bool:
    return name.lower().endswith(".zip") or data[:4] == b"PK\x03\x04"


def b64_files(obj, where: str) -> Dict[str, bytes]:
    if obj is None:
        return {}
    if not isinstance(obj, dict):
        raise InputError("expected an object {relative path: base64 content}", path=[where])
    out = {}
    for k, v in obj.items():
        if not isinstance(v, str):
            raise InputError("expected base64 text", path=[where, k])
        try:
            out[k] = base64.b64decode(v, validate=True)
        except (binascii.Error, ValueError):
            raise InputError("not valid base64", path=[where, k]) from None
    return out


def float_param(request: Request, name: str) -> Optional[float]:
    v = request.query_params.get(name)
    if v is None or v == "":
        return None
    try:
        f = float(v)
    except ValueError:
        raise InputError(f"query parameter {name}: expected a number, got {v!r}") from None
    if not math.isfinite(f):
        raise InputError(f"query parameter {name}: expected a finite number, got {v!r}")
    return f
