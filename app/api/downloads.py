"""The ``Content-Disposition`` header of a download, for any file name a user can give.

Header values are Latin-1 on the wire, and a name may hold any character a data set's
name holds (``Ω-touch``, ``q"uote``), so the name is sent twice (RFC 6266, section 4.3):
``filename*`` with the exact name in UTF-8, percent-encoded (RFC 5987), which every
current browser and curl's ``-J`` prefer, and ``filename`` with an ASCII fallback for the
others, in which no character can end the quoted string early.
"""

from __future__ import annotations

import re
from urllib.parse import quote

#: Characters the ASCII fallback replaces by ``_``: beyond ASCII, controls, quote and
#: backslash (which would end or escape the quoted string), and path separators.
_NOT_PLAIN = re.compile(r'[^\x20-\x7e]|["\\/]')


def attachment(filename: str) -> str:
    """The ``Content-Disposition`` value that saves a download as ``filename``.

    Parameters
    ----------
    filename : str
        The name, any Unicode text.

    Returns
    -------
    str
        ``attachment; filename="ASCII"; filename*=UTF-8''PERCENT-ENCODED``, pure ASCII.
    """
    fallback = _NOT_PLAIN.sub("_", filename)
    return f"attachment; filename=\"{fallback}\"; filename*=UTF-8''{quote(filename, safe='')}"
