"""The Dashboard Server's commands per generation and software version (config/ur_dashboard.yaml).

The replies are checked against the patterns ur_client_library matches them
with (its DashboardClientImplG5 command list and its URSim tests), so a client
that accepts the real robot's replies accepts these. A command the software
is too old for, or that its generation lacks, gets the robot's "could not
understand" reply.
"""
import re

import pytest

from ur3_ft_gripper_description.devices.ur_arm import dashboard_commands, robot_state as rs, software

# ur_client_library's reply patterns, matched whole (std::regex_match).
CLIENT_PATTERNS = {
    'robotmode': r'(?:Robotmode: ).*',
    'safetymode': r'(?:Safetymode: ).*',
    'safetystatus': r'(?:Safetystatus: ).*',
    'running': r'(?:Program running: ).*',
    'get loaded program': r'(?:Loaded program: ).*',
    'isProgramSaved': r'(?:true|false).*',
    'programState': r'(STOPPED|PLAYING|PAUSED) .*',
    'PolyscopeVersion': r'(?:URSoftware ).*',
    'get serial number': r'(?:20).*',
    'get robot model': r'(?:UR).*',
    'saveLog': r'Log saved to disk',
    'close popup': r'closing popup',
    'close safety popup': r'closing safety popup',
    'popup hello': r'showing popup',
    'addToLog hello': r'Added log message',
    # commandGenerateFlightReport's and commandGenerateSupportFile's patterns (not their table's)
    'generate flight report controller': r'(?:Flight Report generated with id:).*',
    'generate support file /programs': r'(?:Completed successfully:).*',
}
CB3_ONLY = ['getUserRole', 'setUserRole PROGRAMMER']
E_SERIES_ONLY = ['version', 'get operational mode', 'set operational mode AUTOMATIC', 'clear operational mode',
                 'is in remote control']


def robot(ur_type, version=None):
    controller = software.for_model(ur_type)
    if version is not None:
        controller = software.ControllerSoftware(ur_type, version, controller.serial_number)
    return rs.RobotState(controller)


def not_understood(command):
    return "could not understand: '%s'" % command


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e', 'ur20'])
@pytest.mark.parametrize('command', sorted(CLIENT_PATTERNS))
def test_every_generation_answers_as_ur_client_library_expects(ur_type, command):
    answer = robot(ur_type).dashboard(command)
    assert re.fullmatch(CLIENT_PATTERNS[command], answer), answer


@pytest.mark.parametrize('command', CB3_ONLY)
def test_user_roles_are_a_cb3s_and_an_e_series_does_not_understand_them(command):
    assert robot('ur5e').dashboard(command) == not_understood(command)
    assert robot('ur3').dashboard(command) != not_understood(command)


@pytest.mark.parametrize('command', E_SERIES_ONLY)
def test_operational_modes_and_remote_control_are_an_e_series_and_a_cb3_does_not_understand_them(command):
    assert robot('ur3').dashboard(command) == not_understood(command)
    assert robot('ur5e').dashboard(command) != not_understood(command)


def test_a_cb3_sets_and_reports_each_user_role_as_ur_client_library_tests_it_on_ursim():
    cb3 = robot('ur3')
    for role in ('NONE', 'PROGRAMMER', 'OPERATOR', 'NONE', 'LOCKED', 'RESTRICTED'):
        assert cb3.dashboard('setUserRole ' + role) == 'Setting user role: ' + role
        assert cb3.dashboard('getUserRole') == role


def test_an_e_series_sets_gets_and_clears_its_operational_mode_as_on_ursim():
    e_series = robot('ur5e')
    assert e_series.dashboard('get operational mode') == 'NONE'  # no operational mode password
    assert e_series.dashboard('set operational mode automatic') == "Operational mode 'automatic' is set"
    assert e_series.dashboard('get operational mode') == 'AUTOMATIC'
    assert e_series.dashboard('clear operational mode').startswith('No longer controlling the operational mode.')
    assert e_series.dashboard('set operational mode MANUAL') == "Operational mode 'MANUAL' is set"
    assert e_series.dashboard('get operational mode') == 'MANUAL'
    e_series.dashboard('clear operational mode')
    assert e_series.dashboard('get operational mode') == 'NONE'


@pytest.mark.parametrize('ur_type, version, command', [
    ('ur5e', (5, 3, 0, 0), 'safetystatus'),       # e-Series 5.4 on
    ('ur3', (3, 10, 0, 0), 'safetystatus'),       # CB3 3.11 on
    ('ur5e', (5, 5, 0, 0), 'get serial number'),  # e-Series 5.6 on
    ('ur3', (3, 11, 0, 0), 'get robot model'),    # CB3 3.12 on
    ('ur5e', (5, 7, 0, 0), 'saveLog'),            # e-Series 5.8 on
    ('ur3', (3, 12, 0, 0), 'generate flight report system'),  # CB3 3.13 on
    ('ur5e', (5, 7, 0, 0), 'generate support file /programs'),  # e-Series 5.8 on
    ('ur5e', (5, 0, 0, 0), 'restart safety'),     # e-Series 5.1 on
])
def test_a_command_newer_than_the_software_is_not_understood_and_the_release_that_added_it_answers(
        ur_type, version, command):
    assert robot(ur_type, version).dashboard(command) == not_understood(command)
    table = dashboard_commands.read()
    added = tuple(int(part) for part in str(table.entries[table.match(command)[0]][
        software.for_model(ur_type).generation]).split('.'))
    assert robot(ur_type, added + (0,) * (4 - len(added))).dashboard(command) != not_understood(command)


def test_commands_are_understood_in_any_case_and_their_argument_keeps_its_own():
    cb3 = robot('ur3')
    assert cb3.dashboard('POLYSCOPEVERSION') == cb3.dashboard('PolyscopeVersion') == cb3.dashboard('polyscopeversion')
    assert cb3.dashboard('ADDTOLOG Mixed Case Text') == 'Added log message'
    assert cb3.log[-1].endswith('Mixed Case Text'), cb3.log[-1]
    # "load installation x" is the longer command, not "load" of a program named "installation x".
    assert cb3.dashboard('load installation default.installation') == 'Loading installation: default.installation'


def test_a_bad_role_or_mode_is_not_understood_and_changes_nothing():
    cb3, e_series = robot('ur3'), robot('ur5e')
    assert cb3.dashboard('setUserRole ADMIN') == not_understood('setUserRole ADMIN')
    assert cb3.dashboard('getUserRole') == 'NONE'
    assert e_series.dashboard('set operational mode fast') == not_understood('set operational mode fast')
    assert e_series.dashboard('get operational mode') == 'NONE'


def test_each_command_of_the_table_either_acts_or_has_a_fixed_reply_and_each_action_has_its_command():
    table = dashboard_commands.read()
    actions = {name[len('_dashboard_'):].replace('_', ' ') for name in dir(rs.RobotState)
               if name.startswith('_dashboard_')}
    assert actions <= set(table.entries), actions - set(table.entries)
    assert [key for key in table.entries if key not in actions and not table.reply(key)] == []


def test_an_e_series_tells_its_full_version_and_a_cb3_only_through_polyscopeversion():
    e_series = robot('ur5e')
    assert e_series.dashboard('version') == e_series.software.version_text == '5.9.4.0'
    assert e_series.dashboard('PolyscopeVersion') == 'URSoftware 5.9.4.0'


def test_flight_reports_take_the_articles_report_types_and_the_support_file_names_the_robot_and_its_day():
    e_series = robot('ur5e')
    ids = [e_series.dashboard('generate flight report ' + kind) for kind in ('controller', 'Software', 'SYSTEM')]
    assert ids == ['Flight Report generated with id: %d' % n for n in (1, 2, 3)]
    assert e_series.dashboard('generate flight report everything') == \
        not_understood('generate flight report everything')
    name = e_series.dashboard('generate support file /programs')
    assert re.fullmatch(r'Completed successfully: ur_%s_\d{4}-\d\d-\d\d_\d\d-\d\d-\d\d\.zip'
                        % e_series.software.serial_number, name), name
    assert e_series.dashboard('generate support file') == not_understood('generate support file')
