"""Sources (video, image folders, OTB/VOT/MOT sequences, cameras), sinks and dataset readers."""

from .datasets import Sequence, discover_sequences, read_mot, read_otb, read_sequence, read_vot
from .sinks import CsvTrackSink, JsonLinesSink, MotSink, VideoSink, prepare_output, read_track_csv
from .sources import FrameSource, ImageFolderSource, VideoSource, open_source

__all__ = [
    "Sequence", "discover_sequences", "read_mot", "read_otb", "read_sequence", "read_vot", "CsvTrackSink",
    "JsonLinesSink", "MotSink", "VideoSink", "prepare_output", "read_track_csv", "FrameSource",
    "ImageFolderSource", "VideoSource", "open_source",
]
