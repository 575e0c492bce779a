"""URDF export of assembled robots and URDF import of monolithic robots as a one-module set.

The conventions of both directions are here; the code is in :mod:`.urdf_export` and :mod:`.urdf_import`.

Export (:func:`export_urdf`)
----------------------------
* The URDF root link is ``base``: the robot's **base frame** (base connector flipped about x). The file
  is independent of where the robot stands; the current ``Robot.base_pose`` is recorded in a comment
  (``robodesign: base_pose = [...]``) and is applied by whoever places the URDF in a scene.
* One URDF link per pinocchio joint, whose frame is the joint frame; it is named ``<joint name>_link``.
  Its ``<inertial>`` is the lumped inertia of everything rigidly attached to that joint
  (``model.inertias[j]``): mass, CoM as the inertial origin (``rpy="0 0 0"``) and the inertia about the
  CoM in joint axes. The root link ``base`` carries ``model.inertias[0]`` (bodies fixed to the base).
* Every pinocchio joint becomes a ``revolute``/``prismatic`` joint (never ``continuous``: that would
  make pinocchio use a 2-coordinate joint). The origin is the joint placement relative to the parent
  joint frame; the axis is ``0 0 1`` or ``0 0 -1`` for a module mounted backwards.
* ``<limit lower upper effort velocity [acceleration]>``; URDF parsers cannot read ``inf``, so an
  infinite limit is written as ±1.7976931348623157e+308 (the largest double) and read back as ±inf.
* ``<dynamics damping="f_v" friction="f_c"/>`` (viscous and Coulomb friction: pinocchio reads them
  into ``model.damping``/``model.friction``). Gear ratio and motor inertia have no URDF equivalent:
  they are written as ``<drivetrain gear_ratio=".." motor_inertia=".."/>`` inside the ``<joint>``
  (URDF parsers ignore unknown tags; :func:`import_urdf` reads it back).
* Collision geometry: boxes, cylinders and spheres as URDF primitives; triangle meshes reference the
  original file with its ``scale``; convex pieces (the ``.wrl`` convex decompositions IMPROV ships,
  or ``convex_meshes=True`` hulls) are written as binary STL files into ``<urdf stem>_meshes/`` next
  to the URDF, because URDF loaders cannot read VRML — one ``<collision>`` per coal object, so the
  URDF has exactly as many collision geometries as ``robot.geom_model`` (obstacles excluded).
  ``<visual>`` elements come from the bodies' visual specs (a ``.wrl`` visual becomes one STL).
* ``mesh_dir_mode="absolute"``: mesh filenames are absolute paths (the URDF loads from anywhere on
  this machine, no package dirs needed). ``"copy"``: referenced mesh files are copied into
  ``<urdf stem>_meshes/`` and referenced relative to the URDF's folder (a self-contained folder;
  pinocchio needs ``package_dirs=[<urdf folder>]`` for relative paths). Only ``copy`` output can be
  re-imported with :func:`import_urdf`, which rejects absolute paths.
* The TCP becomes a fixed joint ``tcp_joint`` and a massless link ``tcp``.

Import (:func:`import_urdf`)
----------------------------
* One module (ID = ``name`` or the URDF robot name) with one body per URDF link (body ID = link
  name) and one joint per URDF joint (joint ID = joint name). Bodies/joints form the URDF tree.
* A URDF joint with an arbitrary axis ``a`` gets a joint frame whose z-axis is ``a``:
  ``pose_parent = origin · R_align`` and ``pose_child = R_alignᵀ`` with ``R_align e_z = a``; for
  ``a = −z``, ``R_align = Rx(π)``. ``continuous`` joints become revolute with limits ±2π (pinocchio
  needs finite bounds for sampling). ``mimic`` joints, ``floating`` and ``planar`` joints are rejected.
* Gripper fingers (joints whose name contains ``finger``) are fixed at q = 0 unless
  ``include_fingers=True``.
* Inertia: URDF gives it about the CoM in the axes of ``<inertial><origin rpy>``; it is rotated
  into the link frame, ``I_link = R I Rᵀ``; the CoM is the inertial origin's ``xyz``.
* Friction: ``<dynamics damping>`` → viscous, ``friction`` → Coulomb. ``<drivetrain>`` (written by
  :func:`export_urdf`) or a transmission's ``<mechanicalReduction>`` give gear ratio/motor inertia.
* Connectors: ``base`` (type ``base``, gender ``f``, pose Rx(π)) on the root link, so the robot's
  base frame is the root link frame; ``eef`` (type ``eef``, gender ``m``, identity pose) on the TCP
  link: ``tcp_link`` if given, else the deepest leaf link (most joints from the root), not counting
  finger links — for the standard ``panda_arm_hand`` URDF this is ``panda_hand``.
* Mesh files: relative paths are relative to the URDF's folder; ``package://NAME/rest`` is looked up
  in ``package_dirs`` (folder ``NAME`` inside one of them, or a folder named ``NAME``) and else in the
  URDF's ancestors (ROS layout ``NAME/urdf/robot.urdf``). The module set's ``root`` is that package
  folder when it contains the URDF, else the URDF's folder; every mesh must resolve inside it
  (absolute paths and ``..`` escapes are rejected with an :class:`InputError` naming the field).
  Missing visual meshes are skipped with a warning (appended to ``warnings``); missing collision
  meshes are an error.
"""
from robodesign.formats.urdf_export import DBL_MAX as DBL_MAX
from robodesign.formats.urdf_export import MESH_DIR_MODES, export_urdf
from robodesign.formats.urdf_import import CONTINUOUS_LIMIT, import_urdf

__all__ = ["export_urdf", "import_urdf", "CONTINUOUS_LIMIT", "MESH_DIR_MODES"]
