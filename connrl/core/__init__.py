"""The thesis's algorithms, knowing no world: returns, lessons, App. A.2 sampling, Fig. 5.1 replay, relaxation
planning (4.2.5), state grouping (6.6.4) and exploration (Boltzmann, Eq. 6.6's weighted Boltzmann and persistence
rule, schedules, stuck detection)."""

from connrl.core.exploration import (
    StuckConfig,
    StuckDetector,
    TemperatureSchedule,
    boltzmann_probabilities,
    boltzmann_select,
    persistence_weights,
    weighted_boltzmann_probabilities,
)
from connrl.core.grouping import GroupedLesson, group_lesson, group_states
from connrl.core.lesson_files import LessonFileError, load_lessons, save_lessons
from connrl.core.lessons import Lesson, LessonMemory, LessonRecorder, recency_index
from connrl.core.replay import (
    REPAIRS,
    QFunction,
    ReplayParams,
    batch_targets,
    repair_step,
    replay_ahc,
    replay_q,
    replay_q_reference,
)
from connrl.core.returns import lambda_returns, td_lambda_target
from connrl.core.rollout import TrialStats, run_trial

__all__ = ["REPAIRS", "GroupedLesson", "Lesson", "LessonFileError", "LessonMemory", "LessonRecorder", "QFunction",
           "ReplayParams", "StuckConfig", "StuckDetector", "TemperatureSchedule", "TrialStats", "batch_targets",
           "boltzmann_probabilities", "boltzmann_select", "group_lesson", "group_states", "lambda_returns",
           "load_lessons", "persistence_weights", "recency_index", "repair_step", "replay_ahc", "replay_q",
           "replay_q_reference", "run_trial", "save_lessons", "td_lambda_target", "weighted_boltzmann_probabilities"]
