"""rosbag2 sqlite3 storage files: the read-only reader, the WAL copy, and the followed tail."""
