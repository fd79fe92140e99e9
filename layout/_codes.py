"""Integer codes shared by the builder, the kernels and the reports (one place only)."""

# Particle roles.
ITEM, GROUP, OBSTACLE = 0, 1, 2

# Constraint modes: equality, C >= 0 (keep at least), C <= 0 (keep at most).
EQ, MIN, MAX = 0, 1, 2
MODE_NAMES = {"eq": EQ, "min": MIN, "max": MAX}

# Stiffness schedules k_l for iteration l >= 1 (Weiss et al. Sec. 3.1):
# CONSTANT k0; DECAY 1 - (1 - k0)^(M / l) (soft constraints fade so hard ones win);
# GROW 1 - (1 - k0)^(l / M) (collisions harden as the layout settles).
CONSTANT, DECAY, GROW = 0, 1, 2
SCHEDULE_NAMES = {"constant": CONSTANT, "decay": DECAY, "grow": GROW}

# Orientation modes: FACE = yaw relative to the direction towards the partner (paper
# Sec. 3.3.10); PARALLEL = yaw relative to the partner's yaw, modulo pi.
FACE, PARALLEL = 0, 1

# Curve types of non-rigid groups.
SEGMENT, ARC = 0, 1

# Collision models: the paper's bounding spheres, or exact oriented boxes (SAT).
SPHERE, BOX = 0, 1
COLLISION_NAMES = {"sphere": SPHERE, "box": BOX}

# Constraint kinds, in the order of the energy breakdown.
KINDS = (
    "distance",
    "lane",
    "heat",
    "symmetry",
    "balance",
    "wall_distance",
    "wall_orientation",
    "orientation",
    "stack",
    "curve",
    "boundary",
    "collision",
    "access",
)
(
    K_DISTANCE,
    K_LANE,
    K_HEAT,
    K_SYMMETRY,
    K_BALANCE,
    K_WALL_DISTANCE,
    K_WALL_ORIENTATION,
    K_ORIENTATION,
    K_STACK,
    K_CURVE,
    K_BOUNDARY,
    K_COLLISION,
    K_ACCESS,
) = range(len(KINDS))

# Energy weights g_j of Eq. (1): the paper's 150 for collision and accessibility, 20 for
# the wall constraints (layout boundary included), 1 for the rest.
ENERGY_WEIGHTS = tuple(
    150.0 if k in ("collision", "access") else 20.0 if k.startswith(("wall", "boundary")) else 1.0
    for k in KINDS
)
