"""Read an .rrd file back into numpy arrays (for tests, and to compare recorded runs in Python).

    from explorer.view.rerun.read import read_rrd
    for rec in read_rrd("run.rrd"):
        rec.name, rec.series["/valve/lift"]["value"], rec.series["/valve/lift"]["time"]

Per entity, the temporal rows are gathered over all chunks and sorted by the `step` timeline
(when present); static components are kept as Python lists. Uses rerun.chunk.RrdReader, which
needs the file's footer: the recording must be closed (disconnected) before reading.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

ROW_ID = "rerun.controls.RowId"


@dataclass
class RecordedRun:
    recording_id: str
    application_id: str
    name: str | None = None
    # entity path -> {timeline name: array, component name: array}; one row per logged row
    temporal: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    # entity path -> {component name: python value of the (last) static row}
    static: dict[str, dict[str, object]] = field(default_factory=dict)

    @property
    def series(self) -> dict[str, dict[str, np.ndarray]]:
        """Entities holding Scalars, as {timeline: array, "value": float array}."""
        out = {}
        for path, cols in self.temporal.items():
            if "Scalars:scalars" in cols:
                entry = {k: v for k, v in cols.items() if ":" not in k}
                entry["value"] = cols["Scalars:scalars"]
                out[path] = entry
        return out


def _component_array(column, rows: int):
    """A list<...> column with one item per row -> numpy array (N,) or (N, k); else a list."""
    import pyarrow as pa

    lengths = column.value_lengths().to_numpy(zero_copy_only=False)
    if rows and np.all(lengths == 1):
        values = column.flatten()
        if pa.types.is_fixed_size_list(values.type):
            k = values.type.list_size
            return values.flatten().to_numpy(zero_copy_only=False).reshape(-1, k)
        if pa.types.is_floating(values.type) or pa.types.is_integer(values.type):
            return values.to_numpy(zero_copy_only=False)
        return np.asarray(values.to_pylist(), dtype=object)
    return column.to_pylist()


def _timeline_array(column) -> np.ndarray:
    import pyarrow as pa

    if pa.types.is_duration(column.type) or pa.types.is_timestamp(column.type):
        column = column.cast(pa.int64())
    return column.to_numpy(zero_copy_only=False)


def read_rrd(path) -> list[RecordedRun]:
    """Every recording in the file, in file order."""
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    runs = []
    for store in reader.recordings():
        run = RecordedRun(recording_id=store.recording_id, application_id=store.application_id)
        parts: dict[str, dict[str, list]] = {}
        for chunk in reader.stream(store=store):
            batch = chunk.to_record_batch()
            timelines = set(chunk.timeline_names)
            entity = chunk.entity_path
            if chunk.is_static:
                slot = run.static.setdefault(entity, {})
                for name in batch.schema.names:
                    if name != ROW_ID:
                        values = batch.column(name).to_pylist()
                        slot[name] = values[-1] if values else None
                continue
            slot = parts.setdefault(entity, {})
            for name in batch.schema.names:
                if name == ROW_ID:
                    continue
                column = batch.column(name)
                if name in timelines or not name.count(":"):
                    slot.setdefault(name, []).append(_timeline_array(column))
                else:
                    slot.setdefault(name, []).append(_component_array(column, batch.num_rows))
        for entity, cols in parts.items():
            merged = {}
            for name, pieces in cols.items():
                if all(isinstance(p, np.ndarray) for p in pieces):
                    merged[name] = np.concatenate(pieces)
                else:
                    merged[name] = [x for p in pieces for x in (list(p) if not isinstance(p, list) else p)]
            if "step" in merged:
                order = np.argsort(merged["step"], kind="stable")
                merged = {k: (v[order] if isinstance(v, np.ndarray) else [v[i] for i in order]) for k, v in merged.items()}
            run.temporal[entity] = merged
        names = run.static.get("/__properties", {}).get("RecordingInfo:name")
        run.name = names[0] if isinstance(names, list) and names else names
        runs.append(run)
    return runs


def read_blueprint_views(path) -> list[dict]:
    """The views of the blueprint sent last to the file (a live session's file holds one per layout
    sent): [{"class": "TimeSeries", "origin": "/", "contents": [...], "name": ...}]."""
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    store = _last_sent(reader, reader.blueprints())
    if store is None:
        return []
    views: dict[str, dict] = {}
    for chunk in reader.stream(store=store):
        entity = chunk.entity_path
        if entity == "/time_panel":
            _time_panel(chunk, views)
            continue
        if not entity.startswith("/view/"):
            continue
        view_id = entity.split("/")[2]
        view = views.setdefault(view_id, {})
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            if ":" not in name or name == ROW_ID:  # row ids and the blueprint's own timelines
                continue
            values = batch.column(name).to_pylist()
            if not values or values[-1] is None:
                continue
            last = values[-1]
            if name.endswith("class_identifier"):
                view["class"] = last[0]
            elif name.endswith("space_origin"):
                view["origin"] = last[0]
            elif name.endswith("display_name"):
                view["name"] = last[0]
            elif name.endswith("ViewContents:query"):
                view["contents"] = list(last)
            elif name == "PlotLegend:corner":  # 1 LeftTop, 2 RightTop, 3 LeftBottom, 4 RightBottom
                view["legend_corner"] = ("LeftTop", "RightTop", "LeftBottom", "RightBottom")[last[0] - 1]
            elif name == "VisibleTimeRanges:ranges":
                view["time_ranges"] = {r["timeline"]: (r["range"]["start"], r["range"]["end"]) for r in last}
    panel = views.pop("__time_panel__", None)
    return list(views.values()) + ([panel] if panel else [])


def _last_sent(reader, stores):
    """The store whose newest row was logged last. `RrdReader.blueprints()` lists a file's
    blueprints in no fixed order (the first of three was another one from run to run); row ids
    are rerun's TUIDs, whose big-endian bytes begin with the time they were made."""
    newest = {}
    for store in stores:
        for chunk in reader.stream(store=store):
            ids = chunk.to_record_batch().column(ROW_ID).to_pylist()
            if ids:
                newest[store] = max(newest.get(store, b""), max(ids))
    return max(newest, key=newest.get) if newest else (stores[0] if stores else None)


def _time_panel(chunk, views: dict) -> None:
    """The time panel's timeline, fps and playback speed, as a pseudo-view {"class": "TimePanel"}."""
    batch = chunk.to_record_batch()
    panel = views.setdefault("__time_panel__", {"class": "TimePanel"})
    for name in batch.schema.names:
        if ":" not in name or name == ROW_ID:
            continue
        values = batch.column(name).to_pylist()
        if not values or values[-1] is None:
            continue
        last = values[-1]
        for key in ("timeline", "fps", "playback_speed"):
            if name.endswith(":" + key):
                panel[key] = last[0] if isinstance(last, list) else last
