"""The table of a sweep: one row per run, the varied inputs then the figures (SI units in the
names), as numpy columns; written as Parquet or CSV by the file's extension, atomically
(explorer.core.outputs). pyarrow (which rerun-sdk brings) is imported only to write or convert.

An interrupted sweep keeps the runs that finished: the table says `complete = False` and how
many runs were planned. Parquet carries that in the schema's metadata (explorer.complete,
explorer.runs_planned, ...), CSV in leading `# key: value` comment lines, which
`numpy.genfromtxt`, `pandas.read_csv(comment="#")` and `read_table` here skip or read.
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from ..core.errors import InputError
from ..core.outputs import as_output, write_output

FORMATS = (".parquet", ".csv")
# integer-valued figures, stored as integers (counts, the run index, the failure flag); a count
# column with a failed run's NaN in it stays float so the failure reads NaN in every format
# (a cast would make it int64's minimum, -9223372036854775808)
INTEGER_COLUMNS = frozenset({"run", "separations", "seat_impacts", "run_failed"})


@dataclass(frozen=True)
class SweepTable:
    """`columns`: name -> numpy array (one entry per finished run, in run order);
    `metadata`: scene, keys, distributions, seed, complete, runs_planned."""

    columns: Mapping[str, np.ndarray]
    metadata: Mapping[str, Any] = field(default_factory=dict)

    @staticmethod
    def build(columns: dict, metadata: dict) -> "SweepTable":
        frozen = {}
        for name, values in columns.items():
            arr = np.asarray(values)
            if name in INTEGER_COLUMNS and arr.dtype.kind == "f" and not np.isnan(arr).any():
                arr = arr.astype(np.int64)
            arr.setflags(write=False)
            frozen[name] = arr
        return SweepTable(MappingProxyType(frozen), MappingProxyType(dict(metadata)))

    @property
    def complete(self) -> bool:
        return bool(self.metadata.get("complete", True))

    def __len__(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def to_arrow(self):
        import pyarrow as pa

        meta = {f"explorer.{k}".encode(): json.dumps(v).encode() for k, v in self.metadata.items()}
        table = pa.table({k: pa.array(v) for k, v in self.columns.items()})
        return table.replace_schema_metadata(meta)

    def to_pandas(self):
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_pandas needs pandas (pip install pandas); .columns holds numpy arrays") from None
        frame = pd.DataFrame({k: np.asarray(v) for k, v in self.columns.items()})
        frame.attrs.update(self.metadata)
        return frame

    def csv_text(self) -> str:
        buf = io.StringIO()
        for key, value in self.metadata.items():
            buf.write(f"# {key}: {json.dumps(value)}\n")
        names = list(self.columns)
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(names)
        cols = [np.asarray(self.columns[n]) for n in names]
        for row in zip(*[c.tolist() for c in cols]):
            writer.writerow([repr(x) if isinstance(x, float) else x for x in row])
        return buf.getvalue()

    def parquet_bytes(self) -> bytes:
        import pyarrow as pa
        import pyarrow.parquet as pq

        sink = pa.BufferOutputStream()
        pq.write_table(self.to_arrow(), sink)
        return sink.getvalue().to_pybytes()

    def write(self, out) -> None:
        """Write to a checked explorer.core.outputs.Output (or a path) by its extension."""
        out = as_output(out, "--output")
        kind = table_format(out.name)
        write_output(out, self.parquet_bytes() if kind == ".parquet" else self.csv_text())


def table_format(name: str) -> str:
    lower = str(name).lower()
    for ext in FORMATS:
        if lower.endswith(ext):
            return ext
    raise InputError(str(name), "--output", f"the table's file name must end in {' or '.join(FORMATS)}")


def read_table(path) -> SweepTable:
    """A table written by SweepTable.write (Parquet or CSV), with its metadata."""
    kind = table_format(str(path))
    if kind == ".parquet":
        import pyarrow.parquet as pq

        table = pq.read_table(path)
        meta = {k.decode()[len("explorer."):]: json.loads(v) for k, v in (table.schema.metadata or {}).items()
                if k.startswith(b"explorer.")}
        return SweepTable.build({n: table.column(n).to_numpy() for n in table.column_names}, meta)
    meta, lines = {}, []
    with open(path, encoding="utf-8") as handle:
        for line in handle:
            if line.startswith("# "):
                key, _, value = line[2:].partition(": ")
                meta[key] = json.loads(value)
            else:
                lines.append(line)
    rows = list(csv.reader(lines))
    names = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]], dtype=float).reshape(-1, len(names))
    return SweepTable.build({n: data[:, j] for j, n in enumerate(names)}, meta)
