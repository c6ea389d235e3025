"""The flight recorder: recordings written to MCAP and read back from MCAP, rosbag1 and rosbag2. No Qt.

``writer.py`` (``McapSink``: the file, in its own thread), ``schema.py`` (definitions), ``ingest.py``
(``RobotRecorder``: one robot's topics and operator events into a sink), ``files.py`` (opening any
recording), ``recover.py`` (a file cut short by a crash). The CLI is ``rcon record``
(``cli/record_cmd.py``); playing a recording as a robot is ``sim/playback.py``. See docs/recording.md.
"""
