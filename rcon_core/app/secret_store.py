"""Where the app keeps each robot's rosauth secret: the OS credential store, through ``keyring``.

Decisions
    A secret is keyed by the robot's URL under the service name ``rcon``.  Where no credential store
    exists (``keyring``'s fail or null backend, a plain-text backend, or ``keyring`` not installed), the
    secret is kept in memory for this run only and asked for again at the next start: it is never written
    to a file by the app.  A store that raises (locked, denied) is logged and treated the same way.
    No Qt here: the connection settings dialog shows :attr:`SecretStore.where` to say which of the two
    applies.
"""

from __future__ import annotations

import logging
from typing import Any

log = logging.getLogger(__name__)

SERVICE = "rcon"
#: keyring backends that are not a credential store (they fail, drop, or write plain text)
_NOT_A_STORE = ("fail.Keyring", "null.Keyring", "PlaintextKeyring", "UncryptedFileKeyring")


def _backend() -> Any:
    try:
        import keyring
    except ImportError:
        return None
    try:
        backend = keyring.get_keyring()
    except Exception:  # a broken keyring configuration must not keep the app from starting
        log.warning("no usable credential store", exc_info=True)
        return None
    name = f"{type(backend).__module__.rsplit('.', 1)[-1]}.{type(backend).__name__}"
    if any(name.endswith(bad) or type(backend).__name__ == bad for bad in _NOT_A_STORE):
        return None
    return backend


class SecretStore:
    """rosauth secrets by robot URL: the OS credential store when there is one, else this run's memory."""

    def __init__(self) -> None:
        self._memory: dict[str, str] = {}

    @property
    def persistent(self) -> bool:
        """Whether a secret set now is still there after a restart (an OS credential store exists)."""
        return _backend() is not None

    @property
    def where(self) -> str:
        """One sentence for the operator: where a secret entered now is kept."""
        if self.persistent:
            return "kept in the system's credential store"
        return "no credential store on this system: kept in memory until RCON quits, asked again at the next start"

    def get(self, url: str) -> str | None:
        if url in self._memory:
            return self._memory[url]
        backend = _backend()
        if backend is None:
            return None
        try:
            return backend.get_password(SERVICE, url) or None
        except Exception as exc:
            log.warning("reading the secret for %s from the credential store failed: %s", url, exc)
            return None

    def set(self, url: str, secret: str) -> bool:
        """Keep ``secret`` for ``url``; True when it went into the credential store (else memory only)."""
        self._memory[url] = secret
        backend = _backend()
        if backend is None:
            return False
        try:
            backend.set_password(SERVICE, url, secret)
        except Exception as exc:
            log.warning("storing the secret for %s in the credential store failed: %s", url, exc)
            return False
        return True

    def forget(self, url: str) -> None:
        self._memory.pop(url, None)
        backend = _backend()
        if backend is None:
            return
        try:
            if backend.get_password(SERVICE, url) is not None:
                backend.delete_password(SERVICE, url)
        except Exception as exc:
            log.warning("removing the secret for %s from the credential store failed: %s", url, exc)
