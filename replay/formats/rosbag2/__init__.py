"""rosbag2 directories: metadata.yaml (:mod:`.metadata`), the reader (:mod:`.reader`) with
its copies of a cut-short or damaged SQLite storage (:mod:`.reindex`, :mod:`.salvage`), and
the writer (:mod:`.writer`) with camlog's storage plugins (:mod:`.storage_plugins`).

A rosbag2 folder with one MCAP storage file is read by the MCAP reader
(:func:`replay.formats.open_reader`). The modules that need ``rosbags`` are imported when
the format is first used, not here.
"""
