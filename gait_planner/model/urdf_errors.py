"""The importer's one error type (`gait_planner.model.urdf_import`, `.urdf_mirror`)."""


class UrdfError(ValueError):
    """A description the importer cannot plan for; the message names the joint or link."""
