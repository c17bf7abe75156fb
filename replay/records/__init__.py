"""Typed JSON records of camlog's well-known topics (see :mod:`replay.topics`)."""

from .base import JsonRecord, from_json, to_json
from .calibration import (
    BoardSummary,
    BoardWarpSummary,
    CalibrationSummary,
    CameraSummary,
    CoverageSummary,
    EvidenceSummary,
    LensOrderSummary,
    OptionsSummary,
    ParameterEstimate,
    RangeProgress,
    RejectedJointView,
    RejectedView,
    StereoSummary,
    StereoTruth,
    TangentialSummary,
    TimeOffsetSummary,
    UncertaintySummary,
    ViewResiduals,
)
from .processed import ProcessedOutput, ProcessedOutputs, outputs_by_topic
from .resync import OffsetStats, ResyncStats
from .rig import RigCameraSummary, RigPairSummary, RigSummary
from .scenario import (
    RenderView,
    Scenario,
    ScenarioCamera,
    ScenarioDrift,
    ScenarioLatency,
    ScenarioTarget,
)
from .time_offset import TimeOffset

__all__ = [
    "BoardSummary",
    "BoardWarpSummary",
    "CalibrationSummary",
    "CameraSummary",
    "CoverageSummary",
    "EvidenceSummary",
    "JsonRecord",
    "LensOrderSummary",
    "OffsetStats",
    "OptionsSummary",
    "ParameterEstimate",
    "ProcessedOutput",
    "ProcessedOutputs",
    "RangeProgress",
    "RejectedJointView",
    "RejectedView",
    "RenderView",
    "ResyncStats",
    "RigCameraSummary",
    "RigPairSummary",
    "RigSummary",
    "Scenario",
    "ScenarioCamera",
    "ScenarioDrift",
    "ScenarioLatency",
    "ScenarioTarget",
    "StereoSummary",
    "StereoTruth",
    "TangentialSummary",
    "TimeOffset",
    "TimeOffsetSummary",
    "UncertaintySummary",
    "ViewResiduals",
    "from_json",
    "outputs_by_topic",
    "to_json",
]
