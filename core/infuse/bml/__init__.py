"""BML: parse Behavior Markup Language, schedule it, report feedback.

``parse_bml``/``parse_bml_file`` give a plain :class:`BmlDocument`; a :class:`Scheduler` turns its blocks
into :class:`Activation` records (controller kind, parameters, global sync times) and feedback events.
Behaviour elements are handled by plugins (hook ``infuse_bml_behaviours``, see :mod:`infuse.bml.behaviours`);
generators add behaviours to a block before it is scheduled (hook ``infuse_bml_generators``, see
:mod:`infuse.bml.generate`).
"""
from __future__ import annotations

from .behaviours import BehaviourContext, BehaviourError, BehaviourPlan, handlers_from, installed_handlers
from .feedback import (
    BlockPrediction, BlockProgress, FeedbackBus, GeneratedBml, SyncPointProgress, WarningFeedback, feedback_xml,
)
from .generate import GenerationError, Generation, GeneratorContext, installed_generators
from .model import Behaviour, Block, BmlDocument, Constraint, Issue, Node
from .parse import DEFAULT_MAX_BYTES, parse_bml, parse_bml_file
from .schedule import Activation, BlockSchedule, Scheduler
from .speech import EngineSpeechTimer, EstimatedSpeechTimer, SpeechTimer, SpeechTiming
from .sync import STANDARD_SYNC_POINTS, SyncRef, SyncRefError, TimingError, TimingModel, parse_sync_ref

__all__ = [
    "BehaviourContext", "BehaviourError", "BehaviourPlan", "handlers_from", "installed_handlers",
    "BlockPrediction", "BlockProgress", "FeedbackBus", "GeneratedBml", "SyncPointProgress", "WarningFeedback",
    "feedback_xml", "GenerationError", "Generation", "GeneratorContext", "installed_generators",
    "Behaviour", "Block", "BmlDocument", "Constraint", "Issue", "Node",
    "DEFAULT_MAX_BYTES", "parse_bml", "parse_bml_file",
    "Activation", "BlockSchedule", "Scheduler",
    "EngineSpeechTimer", "EstimatedSpeechTimer", "SpeechTimer", "SpeechTiming",
    "STANDARD_SYNC_POINTS", "SyncRef", "SyncRefError", "TimingError", "TimingModel", "parse_sync_ref",
]
