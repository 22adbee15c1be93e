"""ros_control's controller_manager as ur_robot_driver sets it up, without ROS.

Which controllers exist comes from ur_robot_driver's config/<ur_type>_controllers.yaml
(every section with a `type`, except the hardware settings); which are
started and which only loaded comes from the `controllers` and
`stopped_controllers` arguments of <ur_type>_bringup.launch, as its
spawners do. Only the controllers of those two lists are loaded.

switch() follows controller_manager_msgs/SwitchController: STRICT fails the
whole switch on any unknown, not running or already running name, and
BEST_EFFORT skips those; strictness 0 is taken as BEST_EFFORT (with a
warning, as the controller_manager does). Every commanding controller
claims all six joints, so two of them can never run together
(ur_robot_driver's controllers.md: "only one of the following can be active
at one time"); a switch that would make them is refused whatever the strictness.
"""

import yaml
from ... import yaml_data

# controller type -> hardware interface of its claimed joints (none: read-only)
CLAIMS = {
    'position_controllers/ScaledJointTrajectoryController': 'scaled_controllers::ScaledPositionJointInterface',
    'position_controllers/JointTrajectoryController': 'hardware_interface::PositionJointInterface',
    'velocity_controllers/ScaledJointTrajectoryController': 'scaled_controllers::ScaledVelocityJointInterface',
    'velocity_controllers/JointTrajectoryController': 'hardware_interface::VelocityJointInterface',
    'velocity_controllers/JointGroupVelocityController': 'hardware_interface::VelocityJointInterface',
    'pass_through_controllers/JointTrajectoryController': 'hardware_interface::JointTrajectoryInterface',
    'pass_through_controllers/CartesianTrajectoryController': 'hardware_interface::CartesianTrajectoryInterface',
    'ros_controllers_cartesian/TwistController': 'hardware_interface::TwistCommandInterface',
    'pose_controllers/CartesianTrajectoryController': 'hardware_interface::PoseCommandInterface',
    'position_controllers/CartesianTrajectoryController': 'hardware_interface::PositionJointInterface',
}

# The read-only controllers the simulation publishes for; robot_status_controller
# (industrial_msgs, not available here) is not among them.
READ_ONLY_TYPES = ('joint_state_controller/JointStateController',
                   'force_torque_sensor_controller/ForceTorqueSensorController',
                   'scaled_controllers/SpeedScalingStateController')
SIMULATED_TYPES = tuple(CLAIMS) + READ_ONLY_TYPES

BEST_EFFORT = 1
STRICT = 2


class ControllerConfigError(ValueError):
    """The controller configuration or the controller lists cannot be used."""


def read_config(path):
    """A <ur_type>_controllers.yaml as parsed, checked to be ur_robot_driver's; ControllerConfigError if not."""
    try:
        with open(path) as stream:
            data = yaml_data.load(stream)
    except (OSError, yaml.YAMLError) as exc:
        raise ControllerConfigError('%s: %s' % (path, exc))
    if not isinstance(data, dict) or 'ur_hardware_interface' not in data:
        raise ControllerConfigError('%s is not a ur_robot_driver controller configuration '
                                    '(no ur_hardware_interface section)' % path)
    return data


def controller_sections(data):
    """The controller sections of a parsed configuration: {name: section}, and the joints."""
    joints = list(data['ur_hardware_interface'].get('joints', []))
    sections = {name: section for name, section in data.items()
                if isinstance(section, dict) and 'type' in section}
    return sections, joints


class Controller(object):
    def __init__(self, name, section, joints):
        self.name = name
        self.type = section['type']
        self.section = section
        self.joints = list(section.get('joints', joints))
        self.interface = CLAIMS.get(self.type)
        self.state = 'initialized'

    @property
    def commanding(self):
        return self.interface is not None

    @property
    def running(self):
        return self.state == 'running'


class ControllerManager(object):
    """Loaded controllers and their states; switch() as controller_manager's switch_controller."""

    def __init__(self, sections, joints, started, stopped):
        self.joints = list(joints)
        self.controllers = {}
        for name in list(started) + list(stopped):
            if name not in sections:
                raise ControllerConfigError('controller %r is not in the controller configuration (it has %s)'
                                            % (name, ', '.join(sorted(sections))))
            if sections[name]['type'] not in SIMULATED_TYPES:
                raise ControllerConfigError('controller %r (%s) is not simulated: leave it out of the controller '
                                            'lists' % (name, sections[name]['type']))
            self.controllers[name] = Controller(name, sections[name], joints)
        self.order = list(started) + list(stopped)
        ok, message = self.switch(list(started), [], STRICT)
        if not ok:
            raise ControllerConfigError(message)

    def listing(self):
        """[(name, state, type, interface or None, claimed joints)] in load order."""
        return [(c.name, c.state, c.type, c.interface, c.joints if c.commanding else [])
                for c in (self.controllers[n] for n in self.order)]

    def running_commanding(self):
        return [c for c in (self.controllers[n] for n in self.order) if c.running and c.commanding]

    def switch(self, start, stop, strictness):
        """(ok, message): ok False leaves every controller as it was."""
        warnings = []
        if strictness not in (BEST_EFFORT, STRICT):
            warnings.append('strictness %d: give STRICT (2) or BEST_EFFORT (1); taken as BEST_EFFORT'
                            % strictness)
            strictness = BEST_EFFORT
        to_stop, to_start = [], []
        for names, chosen, verb, unusable, state_problem in (
                (stop, to_stop, 'stop', lambda c: not c.running, 'since it is not running'),
                (start, to_start, 'start', lambda c: c.running and c not in to_stop, 'since it is already running')):
            for name in names:
                controller = self.controllers.get(name)
                if controller is None or unusable(controller):
                    problem = ('Could not %s controller with name %s because no controller with this name exists'
                               % (verb, name) if controller is None else
                               'Could not %s controller %s %s' % (verb, name, state_problem))
                    if strictness == STRICT:
                        return False, problem
                    warnings.append(problem)
                    continue
                chosen.append(controller)
        after = [c for c in self.controllers.values() if (c.running and c not in to_stop) or c in to_start]
        claimed = {}
        for controller in after:
            if not controller.commanding:
                continue
            for joint in controller.joints:
                if joint in claimed:
                    return False, ('Resource conflict: %s and %s both claim %s; stop one of them in the same '
                                   'switch' % (claimed[joint], controller.name, joint))
                claimed[joint] = controller.name
        for controller in to_stop:
            controller.state = 'stopped'
        for controller in to_start:
            controller.state = 'running'
        return True, '; '.join(warnings)
