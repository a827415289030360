"""Gymnasium environments of the thesis, registered under the ``connrl/`` namespace on import."""

from gymnasium.envs.registration import register, registry

_ENVS = {
    # id: (entry point, default kwargs)
    "connrl/PoleBalancing-v0": ("connrl.envs.pole:PoleBalancingEnv", {}),
    "connrl/PoleBalancingXTheta-v0": ("connrl.envs.pole:PoleBalancingEnv", {"observe": "x_theta"}),
    "connrl/Survival-v0": ("connrl.envs.survival:SurvivalEnv", {}),
    "connrl/CupCollection-v0": ("connrl.envs.cup:CupCollectionEnv", {}),
    "connrl/Robot-DK-v0": ("connrl.envs.robot:RobotTaskEnv", {"task": "DK"}),
    "connrl/Robot-DP-v0": ("connrl.envs.robot:RobotTaskEnv", {"task": "DP"}),
    "connrl/Robot-WFL-v0": ("connrl.envs.robot:RobotTaskEnv", {"task": "WFL"}),
    "connrl/Robot-WFR-v0": ("connrl.envs.robot:RobotTaskEnv", {"task": "WFR"}),
    "connrl/Robot-CHG-v0": ("connrl.envs.robot.recharge:RechargeEnv", {"obs": "high"}),
    "connrl/Robot-CHG-Flat-v0": ("connrl.envs.robot.recharge:RechargeEnv", {"obs": "flat"}),
    "connrl/Robot-CHG-NoXY-v0": ("connrl.envs.robot.recharge:RechargeEnv", {"obs": "high", "xy": False}),  # Ch. 8
    # actions = the shipped learned behaviours; built by connrl.tasks (the world itself knows no learner)
    "connrl/Robot-CHG-Behaviours-v0": ("connrl.tasks.recharge:BehaviourEnv", {}),
    "connrl/Robot-CHG-Behaviours-NoXY-v0": ("connrl.tasks.recharge:BehaviourEnv", {"xy": False}),  # Ch. 8
}

for _id, (_entry, _kwargs) in _ENVS.items():
    if _id not in registry:
        register(id=_id, entry_point=_entry, kwargs=_kwargs)
