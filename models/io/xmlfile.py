"""The one XML opener of the readers (CAVIAR / PETS2009 ground truth, Tsai calibration)."""

from __future__ import annotations

import gzip
import xml.etree.ElementTree as ET
import zlib
from pathlib import Path

from dbn.errors import FileFormatError

__all__ = ["read_xml_root"]


def read_xml_root(path: str | Path, what: str = "XML file") -> ET.Element:
    """The root element of an XML file (``.gz`` read through gzip).

    A missing, unreadable, malformed or truncated file, or one whose declaration names an
    unknown encoding or a multi-byte one expat cannot read (UTF-7, UTF-32, Shift-JIS, ...),
    is a :class:`~dbn.errors.FileFormatError` naming the file (and the line where the
    parser stopped); never a raw ``ParseError`` / ``LookupError`` / ``ValueError``.
    """
    path = Path(path)
    opener = gzip.open if path.suffix == ".gz" else open
    try:
        with opener(path, "rb") as fh:
            return ET.parse(fh).getroot()
    except FileNotFoundError:
        raise FileFormatError(path, f"no such {what}") from None
    except ET.ParseError as exc:
        line = exc.position[0] if getattr(exc, "position", None) else None
        raise FileFormatError(path, f"not well-formed XML ({exc})", line) from None
    except (LookupError, UnicodeError) as exc:  # e.g. encoding="u-f-8" in the declaration
        raise FileFormatError(path, f"XML in an unknown or wrong encoding ({exc})", 1) from None
    except ValueError as exc:  # expat: "multi-byte encodings are not supported" (UTF-7, Shift-JIS)
        raise FileFormatError(path, f"XML in an encoding the parser cannot read ({exc}): save "
                                    "it as UTF-8", 1) from None  # fmt: skip
    except (OSError, EOFError, zlib.error) as exc:
        raise FileFormatError(path, f"unreadable {what} ({exc})") from None
