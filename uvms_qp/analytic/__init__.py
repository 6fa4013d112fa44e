"""Closed-form redundancy-resolution schemes of the source papers, on plain matrices.

No robot model and no solver: every function takes Jacobians, rates, gradients or screws and
returns rates. Each docstring cites its paper (authors, year) and equation. Modules, one concept
each:

- :mod:`.inverses`: pseudoinverse, weighted pseudoinverse, damped least squares, projector;
- :mod:`.gradient_projection`: projected gradient, normalised multi-objective form;
- :mod:`.task_priority`: two-task and recursive task priority, singularity-robust variant;
- :mod:`.manipulability`: manipulability, its gradient, the dexterous task priority of
  Soylu et al. (2007);
- :mod:`.singularity_consistent`: Nenchev and Tsumaki's singularity-consistent method and the
  4-DOF arm's vector fields;
- :mod:`.motion_distribution`, :mod:`.joint_limits`, :mod:`.payload`, :mod:`.fuzzy`:
  Wang et al. (2017);
- :mod:`.screws`, :mod:`.davies`: dos Santos et al.'s (2006) screws, Davies method and virtual
  chains.
"""

from .davies import (
    PPPS_NAMES,
    davies_direct,
    davies_solve,
    kinematic_constraint_inverse,
    network_matrix,
    planar_uvms_screws,
    ppps_screws,
)
from .fuzzy import DEFAULT_RULES, FuzzyRules, FuzzyWeights, fuzzy_weights, memberships
from .gradient_projection import (
    PROJECTORS,
    gradient_projection,
    multi_objective_gradient_projection,
    normalized_gradient,
)
from .inverses import damped_pinv, null_space_projector, pinv, weighted_pinv
from .joint_limits import (
    LIMIT_CLEARANCE,
    joint_limit_gradient,
    joint_limit_gradient_bound,
    joint_limit_index,
    joint_limit_weights,
)
from .manipulability import (
    dexterous_task_priority,
    jacobian_derivatives,
    manipulability,
    manipulability_gradient,
    shaping_function,
    sign_switch,
)
from .motion_distribution import motion_distribution
from .payload import (
    payload_moment,
    payload_objective,
    payload_objective_gradient,
    static_tilt,
    vehicle_payload_moment,
)
from .screws import (
    planar_chain_points,
    planar_chain_screws,
    planar_rows,
    prismatic_screw,
    revolute_screw,
    screw_jacobian,
    screw_to_twist_at,
    screw_transform,
    skew,
)
from .singularity_consistent import (
    column_augmented_jacobian,
    end_point_field,
    sc_arm_jacobian,
    sc_arm_position,
    sc_blend,
    sc_vector_field,
    self_motion_field,
    shoulder_term,
    signed_minor_null_vector,
    singularity_crossings,
)
from .task_priority import (
    closed_loop_reference,
    recursive_task_priority,
    singularity_robust_task_priority,
    sr_task_priority_closed_loop,
    task_priority,
)

__all__ = [
    "DEFAULT_RULES",
    "LIMIT_CLEARANCE",
    "PPPS_NAMES",
    "PROJECTORS",
    "FuzzyRules",
    "FuzzyWeights",
    "closed_loop_reference",
    "column_augmented_jacobian",
    "damped_pinv",
    "davies_direct",
    "davies_solve",
    "dexterous_task_priority",
    "end_point_field",
    "fuzzy_weights",
    "gradient_projection",
    "jacobian_derivatives",
    "joint_limit_gradient",
    "joint_limit_gradient_bound",
    "joint_limit_index",
    "joint_limit_weights",
    "kinematic_constraint_inverse",
    "manipulability",
    "manipulability_gradient",
    "memberships",
    "motion_distribution",
    "multi_objective_gradient_projection",
    "network_matrix",
    "normalized_gradient",
    "null_space_projector",
    "payload_moment",
    "payload_objective",
    "payload_objective_gradient",
    "pinv",
    "planar_chain_points",
    "planar_chain_screws",
    "planar_rows",
    "planar_uvms_screws",
    "ppps_screws",
    "prismatic_screw",
    "recursive_task_priority",
    "revolute_screw",
    "sc_arm_jacobian",
    "sc_arm_position",
    "sc_blend",
    "sc_vector_field",
    "screw_jacobian",
    "screw_to_twist_at",
    "screw_transform",
    "self_motion_field",
    "shaping_function",
    "shoulder_term",
    "sign_switch",
    "signed_minor_null_vector",
    "singularity_crossings",
    "singularity_robust_task_priority",
    "skew",
    "sr_task_priority_closed_loop",
    "static_tilt",
    "task_priority",
    "vehicle_payload_moment",
    "weighted_pinv",
]
