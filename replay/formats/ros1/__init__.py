"""ROS1 bags (v2.0): the reader (:mod:`.reader`), which checks a bag's layout first
(:mod:`.layout`) and reads one without index through a reindexed copy (:mod:`.reindex`),
and the writer (:mod:`.writer`, chunks finished on a worker thread by :mod:`.chunks`).

The modules that need ``rosbags`` are imported when the format is first used, not here.
"""
