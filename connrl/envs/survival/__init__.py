"""Survival task of thesis Ch. 4: an agent collects food on a 25x25 grid while four enemies chase it.

Description
-----------
The 25x25 cell world of thesis 4.1 (docs/RECONSTRUCTION.md, "Survival world", gives the reconstructed
Fig. 4.1 cell for cell). There are four kinds of objects: the agent ("I"), food ("$"), enemies ("E") and
obstacles ("O"). Each step the agent walks to one of the four adjacent cells (into an obstacle: it stays
put, a *collision*). Then each enemy, in turn, stays with probability 0.2 or else moves with the probabilities
of App. A.1: it favours
directions pointing at the agent, more strongly the closer the agent is (:func:`enemy_move_probabilities`).
The agent has two conflicting goals: eat as much food as possible and avoid the enemies. It sees only a
local area through three sensor arrays (food, enemy, obstacle), plus its energy level and a little history.

Action Space
------------
``Discrete(4)``. Indices run clockwise so that the two representations (4.2.3) share one numbering:

=====  =====================  ==========================================  ===
index  ``"global"``           ``"local"`` (relative to orientation)       key
=====  =====================  ==========================================  ===
0      north (row - 1)        front                                       w
1      east  (col + 1)        right                                       d
2      south (row + 1)        back                                        s
3      west  (col - 1)        left                                        a
=====  =====================  ==========================================  ===

``KEYMAP`` maps the keys above to action indices (the same for both representations); ``ACTION_NAMES``
names the actions of each representation. Under ``"local"`` the agent starts each play with a random
orientation and after every step faces the direction it tried to move in (even when it collided).

Observation Space
-----------------
``Box(-0.5, 0.5, (145,), float64)``; every unit is binary, -0.5 (off) or +0.5 (on) (5.3.2). Layout:

=========  =====  =============================================================================
slice      units  content
=========  =====  =============================================================================
0:52       52     food map: 12 "X" (plus, 5 cells) sensors at the cells with L1 distance 1-2, then 20
                  "O" (3x3, 9 cells) at the even-coordinate cells with L1 = 4 or 6, then 20 "Y"
                  (diamond L1 <= 2, 13 cells) at the even-coordinate cells with L1 = 10 (Fig. 4.2a)
52:84      32     enemy map: the same X and O sensors as units 0:32 of the food map (Fig. 4.2b)
84:124     40     obstacle map: one single-cell sensor per cell with L1 = 1..4; cells outside the
                  grid count as obstacles (Fig. 4.2c)
124:140    16     energy, coarse coded: unit k on when ``|E - 5k| < 7.5`` (E capped at 80, see below)
140:144    4      previous action, one-hot (all off at the start of a play)
144        1      the previous move collided with an obstacle
=========  =====  =============================================================================

Within each group sensors are ordered by type (X, O, Y) and then by (row, col) offset from the agent, row
first (``SENSOR_OFFSETS`` / ``SENSOR_TYPES`` list them). A sensor is on when any cell of its receptive field
holds the object. Under ``"global"`` the maps are in the world frame (up = north) and the history holds the
previous *world direction*; under ``"local"`` the maps are rotated so that up = the agent's front and the
history holds the previous *local* action.

Action symmetry (4.2.4). :func:`rotate_observation(obs, k) <rotate_observation>` returns the observation
the agent would get if the whole world were rotated by ``k * 90`` degrees **counter-clockwise** (north
becomes west); it permutes the map units and rotates the previous-action one-hot with them (energy and
the collision bit are unchanged). A "global" agent with ONE network valued for moving north evaluates
"move in direction d" as ``net(rotate_observation(obs, ACTION_ROTATION[d]))``; ``ACTION_ROTATION = (0, 1, 2,
3)`` because rotating the world by ``d`` quarter turns counter-clockwise turns direction ``d`` into north.
All three arrays are invariant under quarter turns, so this is a permutation of units.

Rewards
-------
-1.0 when the agent dies (caught by an enemy or energy 0), +0.4 when it eats food, 0.0 otherwise (4.2.1).
Death takes precedence: eating food and dying in the same step gives -1.0.

Starting State
--------------
Agent at (18, 12); enemies at (1, 12), (6, 6), (6, 12), (6, 18); 15 food pieces on distinct random free
cells (not obstacles, not the agent's or enemies' cells); energy 40; no previous action. Under ``"local"``
a uniformly random initial orientation.

Episode End
-----------
Terminated when the agent has eaten all the food, or it dies: it moves onto an enemy, an enemy moves onto
it, or its energy reaches 0. Truncated (a timeout is not a failure) after ``max_steps`` steps if given.
``info["outcome"]`` is then ``"all_food"``, ``"killed"``, ``"starved"`` or ``"timeout"`` (``None`` during a
play). Energy bounds a play (40 + 15 * 15 = 265 moves at most), so no time limit is needed.

Arguments
---------
``gymnasium.make("connrl/Survival-v0", action_representation="global", render_mode=None, max_steps=None)``

* ``action_representation``: ``"global"`` (Study 1, 4.3.2) or ``"local"`` (Study 2, 4.3.3).
* ``render_mode``: ``None``, ``"ansi"`` (text grid, like Fig. 4.1) or ``"rgb_array"`` (a picture with an
  energy bar and a legend).
* ``max_steps``: optional step limit per play (truncation).

Seeding and environment sets (4.3.1). ``reset(seed=s)`` seeds ``np_random``; the food placement, the local
orientation and all enemy moves then come from it, so a play is reproducible. ``reset(options=
{"layout_seed": k})`` places the food from ``numpy.random.default_rng(k)`` instead (enemy moves and
orientation still come from ``np_random``), so an *environment* (a food layout) can be replayed many times
with different dynamics. :func:`environment_sets` draws the 300 training and 50 test layout seeds of one
experiment from one seed. ``options={"food": [(row, col), ...]}`` places food by hand (taught lessons).

Hooks for agents. :meth:`SurvivalEnv.get_state` / :meth:`SurvivalEnv.set_state` copy the full simulator
state (the "perfect" action model of 4.2.5 steps a copy; by default the copy does not carry the random
generator, so the model samples its own enemy moves). ``info`` always has ``position`` (row, col),
``energy``, ``food_eaten``, ``food_left``, ``orientation`` (0..3 = N, E, S, W), ``collided``, ``steps`` and
``outcome``. :func:`scripted_teacher_action` / :func:`scripted_teacher_lesson` play from the full state
(BFS to the nearest food through cells away from enemies, else retreat) to produce taught lessons (3.7);
on 100 random environments the teacher eats 13.3 of 15 pieces on average and clears 65% of them.
:func:`connrl.tasks.survival.make_taught_lessons` builds the two shipped lessons
(``connrl/data/lessons/survival-global.json``, ``survival-local.json``) from plays where it ate all the food.
:func:`render_rgb` draws any state from :meth:`SurvivalEnv.get_state`.

Differences from the thesis
---------------------------
* The grid, the sensor layouts and the energy code are reconstructions (R) of lost figures
  (docs/RECONSTRUCTION.md, "Survival world"); the
  figures' numbers (25x25, 145 = 52 + 32 + 40 + 16 + 5 inputs, 5/9/13-cell receptive fields) are kept.
* App. A.1 does not say how angle and distance are measured; we use Euclidean geometry on cell centres
  (``dist = hypot(drow, dcol)``, ``angle`` = the unsigned angle between the action's direction and the
  enemy-to-agent vector, in degrees). ``T(dist)`` is used exactly as printed, including its jump at 4.
* The thesis does not say whether enemies may share a cell or stand on food; here they may do both (food
  is never eaten by enemies). An enemy with no free neighbour stays.
* Energy above 82 would switch every energy unit of the reconstructed code off; the code saturates instead
  (energy is capped at 80 *for the code only*; the real energy is not capped).
* The order within a step (move, eat, check contact / all food / starvation, then enemies move one by one)
  is not spelled out in the thesis; when the last piece of food is eaten the play ends before enemies move.
"""

from connrl.envs.survival.env import SurvivalEnv
from connrl.envs.survival.render import render_rgb
from connrl.envs.survival.teacher import scripted_teacher_action, scripted_teacher_lesson
from connrl.envs.survival.world import (
    ACTION_NAMES,
    ACTION_ROTATION,
    AGENT_START,
    DIRECTIONS,
    ENEMY_STARTS,
    GRID_MAP,
    GRID_SIZE,
    KEYMAP,
    N_FOOD,
    N_INPUTS,
    OBS_SLICES,
    OBSTACLES,
    OUTCOMES,
    ROTATION_PERMUTATIONS,
    SENSOR_OFFSETS,
    SENSOR_TYPES,
    enemy_move_probabilities,
    environment_sets,
    rotate_observation,
)

__all__ = ["ACTION_NAMES", "ACTION_ROTATION", "AGENT_START", "DIRECTIONS", "ENEMY_STARTS", "GRID_MAP", "GRID_SIZE",
           "KEYMAP", "N_FOOD", "N_INPUTS", "OBSTACLES", "OBS_SLICES", "OUTCOMES", "ROTATION_PERMUTATIONS",
           "SENSOR_OFFSETS", "SENSOR_TYPES", "SurvivalEnv", "enemy_move_probabilities", "environment_sets",
           "render_rgb", "rotate_observation", "scripted_teacher_action", "scripted_teacher_lesson"]
