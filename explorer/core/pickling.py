"""Pickle for frozen scenes and results across processes (the browser's compute child, a sweep's
workers, a Dask cluster): their read-only mappings (MappingProxyType, which pickle refuses) are
sent as plain dicts and rebuilt as proxies on the other side; `pickle.loads` reads them back."""

from __future__ import annotations

import copyreg
import io
import pickle
from types import MappingProxyType


def _mapping_proxy(items: dict) -> MappingProxyType:
    return MappingProxyType(items)


def dumps(obj) -> bytes:
    buffer = io.BytesIO()
    pickler = pickle.Pickler(buffer, protocol=pickle.HIGHEST_PROTOCOL)
    pickler.dispatch_table = copyreg.dispatch_table.copy()
    pickler.dispatch_table[MappingProxyType] = lambda m: (_mapping_proxy, (dict(m),))
    pickler.dump(obj)
    return buffer.getvalue()
