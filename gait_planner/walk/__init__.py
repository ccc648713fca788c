"""A recorded plan walked in MuJoCo by a reference controller (issue #25).

`reference` joins the recorded half cycle with its mirror images, `mujoco_model` builds the
walker from the recording's /robot_description with the planned feet, `controller` is the
reference stabilising controller, `walk_plan.walk` runs it and summarises the walk,
`summary` puts the summary in words, `recording` writes the walk's MCAP and `rerun_walk` its
rerun view (the simulated walker over the planned one). `gait-planner walk` is the command
(`gait_planner.cli.walk`); parameters are config/walk.yaml.
"""
