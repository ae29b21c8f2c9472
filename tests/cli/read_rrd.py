"""Reads a quadwalk .rrd with Rerun's Python reader (rerun-sdk 0.36.3) and
prints, as one JSON object, what the Rust tests check:

- entities: every entity path with data;
- timelines: every timeline name;
- base_positions: [{sim_time_s, xyz}] of /world/robot/chassis, in time order;
- tile_sinks: [{sim_time_s, sinks_m}] of /world/terrain/tiles (sink of each
  tile = -(z of the box centre + half its thickness)), in time order;
- phase_starts: rows logged to /world/targets/base (one per phase).
"""

import json
import sys

import pyarrow as pa
from rerun.experimental import RrdReader

SKIP = {"log_time", "rerun.controls.RowId"}


def seconds(column):
    return [ns / 1e9 for ns in column.cast(pa.int64()).to_pylist()]


def main(path):
    entities, timelines = set(), set()
    base, tiles = [], []
    phase_starts = 0
    for chunk in RrdReader(path).stream():
        entity = chunk.entity_path
        if entity.startswith("/__"):
            continue
        batch = chunk.to_record_batch()
        names = batch.schema.names
        entities.add(entity)
        timelines.update(n for n in names if n not in SKIP and ":" not in n)
        if entity == "/world/robot/chassis" and "Transform3D:translation" in names and "sim_time" in names:
            for t, xyz in zip(seconds(batch["sim_time"]), batch["Transform3D:translation"].to_pylist()):
                base.append({"sim_time_s": t, "xyz": xyz[0]})
        if entity == "/world/terrain/tiles" and "Boxes3D:centers" in names:
            for t, centres, halves in zip(
                seconds(batch["sim_time"]),
                batch["Boxes3D:centers"].to_pylist(),
                batch["Boxes3D:half_sizes"].to_pylist(),
            ):
                sinks = [-(c[2] + h[2]) for c, h in zip(centres, halves)]
                tiles.append({"sim_time_s": t, "sinks_m": sinks})
        if entity == "/world/targets/base" and "LineStrips3D:strips" in names:
            phase_starts += batch.num_rows
    base.sort(key=lambda r: r["sim_time_s"])
    tiles.sort(key=lambda r: r["sim_time_s"])
    json.dump(
        {
            "entities": sorted(entities),
            "timelines": sorted(timelines),
            "base_positions": base,
            "tile_sinks": tiles,
            "phase_starts": phase_starts,
        },
        sys.stdout,
    )


if __name__ == "__main__":
    main(sys.argv[1])
