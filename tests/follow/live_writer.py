"""A recorder stand-in for the follow tests: writes a sample recording in real time, batch by batch.

Run as a process: ``python tests/follow/live_writer.py OUT --storage mcap --delay 0.1``.
``live`` writes with rosbags' Writer (MCAP chunks closed and flushed per batch; sqlite3 in WAL
mode, one commit per batch); ``relay`` writes finished part files byte range by byte range (split
files, records torn at every boundary), then metadata.yaml; ``split-sqlite`` writes split sqlite3
files in WAL mode.
"""

from __future__ import annotations

import argparse
import sqlite3
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

import yaml
from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Writer

from sample_bags import make_sample_bags as samples

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rosbags.interfaces import Connection


def records(name: str) -> list[samples.Rec]:
    """The sample's messages in log-time order: ``nav2`` (the mission) or ``services``."""
    return samples.nav2_mission() if name == "nav2" else samples.service_calls()


def _batches(items: list[samples.Rec], count: int) -> list[list[samples.Rec]]:
    size = -(-len(items) // count)
    return [items[k : k + size] for k in range(0, len(items), size)]


def write_live(
    out: Path,
    storage: str,
    items: list[samples.Rec],
    batches: int,
    delay: float,
    wal_pages: int = 1000,
    metadata_first: bool = False,
) -> None:
    """Write with rosbags' Writer, making each batch visible before sleeping.

    ``metadata_first``: as rosbag2 does, metadata.yaml appears before the last batch is stored
    and the file closed (rosbags' close then writes the real one over it).
    """
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    writer = Writer(out, version=9, storage_plugin=plugin)
    writer.open()
    store = writer.storage
    if storage == "sqlite3":
        conn = store.conn  # type: ignore[union-attr]
        conn.commit()
        conn.execute("PRAGMA journal_mode=WAL")
        conn.execute(f"PRAGMA wal_autocheckpoint={wal_pages}")
    connections: dict[tuple[str, str], Connection] = {}
    parts = _batches(items, batches)
    for number, batch in enumerate(parts):
        if metadata_first and number == len(parts) - 1:
            (out / "metadata.yaml").write_text("rosbag2_bagfile_information: {version: 9}\n")
            time.sleep(max(delay, 0.5))
        for rec in batch:
            key = (rec.topic, rec.msgtype)
            if key not in connections:
                connections[key] = writer.add_connection(
                    rec.topic,
                    rec.msgtype,
                    msgdef=samples.definition(rec.msgtype),
                    rihs01=samples.TS.hash_rihs01(rec.msgtype),
                )
            data = bytes(samples.TS.serialize_cdr(rec.msg, rec.msgtype))
            writer.write(connections[key], rec.t_ns, data)
        if storage == "mcap":
            store.close_chunk()  # type: ignore[union-attr]
            store.bio.flush()  # type: ignore[union-attr]
        else:
            store.conn.commit()  # type: ignore[union-attr]
        time.sleep(delay)
    writer.close()


def write_relay(
    out: Path, name: str, parts: int, step: int, delay: float, finish: bool, cut: int = 0
) -> None:
    """Write ``parts`` finished MCAP part files into ``out`` ``step`` bytes at a time."""
    bare = out.suffix == ".mcap"  # one bare file, finished by its footer alone
    if not bare:
        out.mkdir()
    items = records(name)
    with tempfile.TemporaryDirectory() as tmp:
        built = []
        for number, part in enumerate(_batches(items, parts)):
            bag = Path(tmp) / f"part{number}"
            write_live(bag, "mcap", part, 20, 0)  # chunks of a twentieth each
            built.append(next(bag.glob("*.mcap")))
        meta = yaml.safe_load((Path(tmp) / "part0" / "metadata.yaml").read_text())
        info = meta["rosbag2_bagfile_information"]
        names = [f"{out.name}_{number}.mcap" for number in range(len(built))]
        info["relative_file_paths"] = names
        info["files"] = [{"path": file} for file in names]
        for source, file in zip(built, names, strict=True):
            data = source.read_bytes()
            if file == names[-1] and cut:
                data = data[:-cut]  # the recorder died: a torn record, no footer
            with (out if bare else out / file).open("wb") as sink:
                for start in range(0, len(data), step):
                    sink.write(data[start : start + step])
                    sink.flush()
                    time.sleep(delay)
    if finish and not bare:
        (out / "metadata.yaml").write_text(yaml.safe_dump(meta))


def write_split_sqlite(
    out: Path, items: list[samples.Rec], parts: int, batches: int, delay: float
) -> None:
    """rosbag2's sqlite3 layout split into ``parts`` files written in WAL mode, one commit per
    batch; each file is closed (its WAL removed) before the next, metadata.yaml last."""
    out.mkdir()
    names: list[str] = []
    topics: dict[tuple[str, str], int] = {}
    for number, part in enumerate(_batches(items, parts)):
        names.append(f"{out.name}_{number}.db3")
        db = sqlite3.connect(out / names[-1], isolation_level=None)
        db.executescript(Sqlite3Writer.SQLITE_SCHEMA)
        db.execute("PRAGMA journal_mode=WAL")
        declared: set[tuple[str, str]] = set()
        for batch in _batches(part, batches):
            db.execute("BEGIN")
            for rec in batch:
                key = (rec.topic, rec.msgtype)
                cid = topics.setdefault(key, len(topics) + 1)
                if key not in declared:
                    declared.add(key)
                    db.execute(
                        "INSERT INTO message_definitions (topic_type, encoding, "
                        "encoded_message_definition, type_description_hash) "
                        "VALUES (?, 'ros2msg', ?, '')",
                        (rec.msgtype, samples.definition(rec.msgtype)),
                    )
                    db.execute(
                        "INSERT INTO topics VALUES (?, ?, ?, 'cdr', '', '')",
                        (cid, rec.topic, rec.msgtype),
                    )
                data = bytes(samples.TS.serialize_cdr(rec.msg, rec.msgtype))
                db.execute(
                    "INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                    (cid, rec.t_ns, data),
                )
            db.execute("COMMIT")
            time.sleep(delay)
        db.close()
    info = {
        "version": 9,
        "storage_identifier": "sqlite3",
        "relative_file_paths": names,
        "files": [{"path": name} for name in names],
    }
    (out / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}))


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--mode", choices=["live", "relay", "split-sqlite"], default="live")
    parser.add_argument("--storage", choices=["mcap", "sqlite3"], default="mcap")
    parser.add_argument("--records", choices=["nav2", "services"], default="nav2")
    parser.add_argument("--batches", type=int, default=20)
    parser.add_argument("--delay", type=float, default=0.1)
    parser.add_argument("--wal-pages", type=int, default=1000)
    parser.add_argument("--parts", type=int, default=2)
    parser.add_argument("--step", type=int, default=4099)
    parser.add_argument("--unfinished", action="store_true", help="never write metadata.yaml")
    parser.add_argument("--cut", type=int, default=0, help="bytes the last file lacks")
    parser.add_argument("--metadata-first", action="store_true", help="as rosbag2 writes it")
    args = parser.parse_args(argv)
    if args.mode == "live":
        items = records(args.records)
        write_live(
            args.out,
            args.storage,
            items,
            args.batches,
            args.delay,
            args.wal_pages,
            metadata_first=args.metadata_first,
        )
    elif args.mode == "split-sqlite":
        items = records(args.records)
        write_split_sqlite(args.out, items, args.parts, args.batches, args.delay)
    else:
        finish = not args.unfinished
        write_relay(args.out, args.records, args.parts, args.step, args.delay, finish, args.cut)
    return 0


if __name__ == "__main__":
    sys.exit(main())
