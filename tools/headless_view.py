#!/usr/bin/env python3
"""RViz without a display: Xvfb, the view launch, the joint sliders beside RViz, a screenshot.

A tool of this repository, not of the installed package: `tools/quickstart
view` runs it when there is no display, and test/view uses the same
HeadlessView, so CI exercises the code path of the README's view command.
`check_screenshot` says whether a screenshot's 3D view holds the robot. Its
programs (Xvfb, xdotool, ImageMagick's import, Pillow) are test dependencies
that tools/quickstart installs.

    python3 tools/headless_view.py -o view.png [--log FILE] [-- name:=value ...]
"""
import collections
import os
import re
import select
import signal
import subprocess
import sys
import time

import numpy
import rospkg
import yaml
from PIL import Image

PACKAGE = 'ur3_ft_gripper_description'
LAUNCH_FILE = 'view_ur3_ft_gripper.launch'
# Starts of the view before a start-up crash of RViz is an error: two crashes in a row happen (a fresh
# root under load, also right after a crash the view test plants), three have not been seen.
RVIZ_STARTS = 4
# xdotool --name patterns: RViz titles its window "<config file> - RViz", and
# joint_state_publisher_gui titles its window after its node name.
RVIZ_WINDOW = ' - RViz$'
SLIDERS_WINDOW = '^Node: .*joint_state_publisher_gui$'
# Pixels that are neither grid nor background and whose red exceeds their
# blue by more than this are the wrench arrows (red force, yellow torque);
# blue exceeding red by more than this is the UR arm's joint caps.
WARM_MARGIN = 30
BLUE_MARGIN = 30
# A grid pixel is the grid colour blended over the background, within this
# many levels per channel (rounding, software rendering).
GRID_TOLERANCE = 4


class ViewError(Exception):
    """The headless view failed; the message is one line naming the problem."""


class RvizCrashed(ViewError):
    """RViz died from a signal before its window showed."""


# roslaunch's line for RViz (a required node) having died; a negative exit code is the signal.
NODE_DIED = re.compile(r'process has died \[pid \d+, exit code (-\d+), cmd \S*/rviz ')


def settings():
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), 'headless_view.yaml')) as f:
        return yaml.safe_load(f)


def default_rviz_config():
    return os.path.join(rospkg.RosPack().get_path(PACKAGE), 'rviz', 'view_ur3_ft_gripper.rviz')


def _colour(text):
    return numpy.array([int(c) for c in str(text).split(';')], dtype=float)


def rviz_colours(rviz_config):
    """Background colour, grid colour and grid alpha of an RViz configuration."""
    with open(rviz_config) as f:
        config = yaml.safe_load(f)
    manager = config['Visualization Manager']
    background = _colour(manager['Global Options']['Background Color'])
    grids = [d for d in manager['Displays'] if d.get('Class') == 'rviz/Grid']
    grid = _colour(grids[0]['Color']) if grids else background
    alpha = float(grids[0].get('Alpha', 1.0)) if grids else 0.0
    return background, grid, alpha


Verdict = collections.namedtuple(
    'Verdict', 'size view_box robot_fraction arm_blue_pixels grid_fraction wrench_pixels shows_robot')


def check_screenshot(path, rviz_config=None, limits=None):
    """What the screenshot's 3D view holds, and whether that is the robot (Verdict)."""
    limits = limits or settings()
    background, grid, alpha = rviz_colours(rviz_config or default_rviz_config())
    image = Image.open(path).convert('RGB')
    pixels = numpy.asarray(image).astype(float)
    # The 3D view: the rows and columns with many pixels of exactly the
    # background colour (widgets and text have at most a few).
    is_background = numpy.all(pixels == background, axis=2)
    rows = numpy.nonzero(is_background.sum(axis=1) > 100)[0]
    cols = numpy.nonzero(is_background.sum(axis=0) > 100)[0]
    if not len(rows) or not len(cols):
        return Verdict(image.size, None, 0.0, 0, 0.0, 0, False)
    top, bottom, left, right = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    view = pixels[top:bottom, left:right]
    area = float(view.shape[0] * view.shape[1])
    is_background = is_background[top:bottom, left:right]
    # Grid: background + a * (grid - background), a between 0 and the grid's alpha.
    offset = view - background
    direction = grid - background
    a = (offset @ direction) / max(float(direction @ direction), 1.0)
    on_line = numpy.abs(offset - a[..., None] * direction).max(axis=2) <= GRID_TOLERANCE
    is_grid = ~is_background & on_line & (a >= 0) & (a <= alpha + 0.05)
    red, blue = view[..., 0], view[..., 2]
    is_wrench = ~is_background & ~is_grid & (red - blue > WARM_MARGIN)
    is_robot = ~is_background & ~is_grid & ~is_wrench
    robot_fraction = is_robot.sum() / area
    arm_blue = int((is_robot & (blue - red > BLUE_MARGIN)).sum())
    shows = bool(robot_fraction >= limits['min_robot_fraction'] and arm_blue >= limits['min_arm_blue_pixels'])
    return Verdict(image.size, (int(left), int(top), int(right), int(bottom)), float(robot_fraction),
                   arm_blue, float(is_grid.sum() / area), int(is_wrench.sum()), shows)


def launch_arg(launch_args, name, default):
    for word in launch_args:
        key, sep, value = word.partition(':=')
        if sep and key == name:
            return value
    return default


class HeadlessView(object):
    """Xvfb + `roslaunch ur3_ft_gripper_description view_ur3_ft_gripper.launch`; stop() ends both.

    The ROS master is the one of ROS_MASTER_URI in `env`: roslaunch starts it
    there when none runs.
    """

    def __init__(self, launch_args=(), log_path=os.devnull, env=None):
        self.launch_args = list(launch_args)
        self.log_path = log_path
        self.settings = settings()
        self.rviz_config = launch_arg(self.launch_args, 'rviz_config', default_rviz_config())
        self.gui = launch_arg(self.launch_args, 'gui', 'true').lower() != 'false'
        self.env = dict(os.environ if env is None else env)
        self.display = None
        self.rviz_window = None
        self.sliders_window = None
        self._xvfb = None
        self._launch = None
        self._log = None
        self._log_start = 0

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()

    def show(self, path, robot_timeout=None):
        """Start the view and save a screenshot once the robot shows in it; the Verdict.

        RViz 1.14 with Mesa's software OpenGL under Xvfb now and then dies
        from a signal in its first seconds: a segmentation fault as it creates
        its GL context, or glibc's abort on a corrupted heap as it loads the
        meshes, after its window has shown. Until the robot has shown, such a
        death is a start-up crash: the view is started once more, and that is
        said, up to RVIZ_STARTS starts. Any other failure is a ViewError.
        """
        self._log = open(self.log_path, 'w')
        self._start_xvfb()
        for start in range(1, RVIZ_STARTS + 1):
            try:
                return self._start_and_screenshot(path, robot_timeout)
            except RvizCrashed as crash:
                if start == RVIZ_STARTS:
                    raise RvizCrashed('%s: %d starts in a row' % (crash, start)) from None
                print('[headless_view] %s; starting the view once more' % crash, file=sys.stderr)
                self._stop_launch()  # the same Xvfb serves the next start
                self.rviz_window = self.sliders_window = None

    def _start_and_screenshot(self, path, robot_timeout):
        start = time.monotonic()
        self._start_launch()
        print('[headless_view] RViz up under Xvfb (%s) after %.0f s; waiting for the robot to show'
              % (self.display, time.monotonic() - start), file=sys.stderr)
        start = time.monotonic()
        verdict = self._wait_for_robot(path, robot_timeout)
        print('[headless_view] the robot showed after %.0f s' % (time.monotonic() - start), file=sys.stderr)
        return verdict

    def _start_launch(self):
        """Start the view launch; wait for RViz's window (and the sliders'); place them."""
        self._log.flush()
        self._log_start = self._log.tell()
        self._launch = subprocess.Popen(['roslaunch', PACKAGE, LAUNCH_FILE] + self.launch_args,
                                        stdout=self._log, stderr=subprocess.STDOUT, env=self.env)
        deadline = time.monotonic() + self.settings['windows_timeout']
        while True:
            self._check_launch_runs('before RViz showed up')
            self.rviz_window = self.rviz_window or self.find_window(RVIZ_WINDOW)
            if self.gui:
                self.sliders_window = self.sliders_window or self.find_window(SLIDERS_WINDOW)
            if self.rviz_window and (self.sliders_window or not self.gui):
                break
            if time.monotonic() > deadline:
                what = 'RViz' if not self.rviz_window else 'the joint sliders (joint_state_publisher_gui)'
                raise ViewError('%s did not open within %d s, see %s'
                                % (what, self.settings['windows_timeout'], self.log_path))
            time.sleep(0.5)
        if self.sliders_window:
            # No window manager: every window opens at 0,0, the sliders over RViz.
            self.xdotool('windowmove', self.sliders_window,
                         str(self.settings['sliders_x']), str(self.settings['sliders_y']))

    def _check_launch_runs(self, when):
        """RvizCrashed if roslaunch has ended because RViz died from a signal, else ViewError if it has ended."""
        if self._launch.poll() is None:
            return
        self._log.flush()
        with open(self.log_path) as f:
            f.seek(self._log_start)
            output = f.read()
        died = NODE_DIED.findall(output)
        if died:
            raise RvizCrashed('RViz died at start-up (signal %d), see %s' % (-int(died[-1]), self.log_path))
        # roslaunch's own reason is its last line (a taken master port, a bad argument...).
        last = ([line.strip() for line in output.splitlines() if line.strip()] or ['no output'])[-1]
        raise ViewError('roslaunch exited (status %d) %s: "%s", see %s'
                        % (self._launch.returncode, when, last, self.log_path))

    def _start_xvfb(self):
        # -displayfd: Xvfb picks a free display itself and writes its number
        # when it accepts connections, so parallel runs never race for one.
        read_end, write_end = os.pipe()
        size = '%dx%dx24' % (self.settings['screen_width'], self.settings['screen_height'])
        self._xvfb = subprocess.Popen(['Xvfb', '-displayfd', str(write_end), '-screen', '0', size,
                                       '-nolisten', 'tcp'],
                                      pass_fds=(write_end,), stdout=self._log, stderr=subprocess.STDOUT)
        os.close(write_end)
        number = b''
        try:
            while not number.endswith(b'\n'):
                ready, _, _ = select.select([read_end], [], [], 30)
                chunk = os.read(read_end, 16) if ready else b''
                if not chunk:
                    raise ViewError('Xvfb did not start, see %s' % self.log_path)
                number += chunk
        finally:
            os.close(read_end)
        self.display = ':' + number.decode().strip()
        # Software OpenGL: Xvfb has no GPU.
        self.env.update(DISPLAY=self.display, LIBGL_ALWAYS_SOFTWARE='1')

    def xdotool(self, *args):
        done = subprocess.run(['xdotool'] + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True, env=self.env)
        return done

    def find_window(self, pattern):
        """The id of the first visible window whose title matches `pattern`, or None."""
        done = self.xdotool('search', '--onlyvisible', '--name', pattern)
        # xdotool search exits 1 while nothing matches.
        return done.stdout.split()[0] if done.returncode == 0 and done.stdout.split() else None

    def capture(self, path):
        """The whole screen into `path` (PNG)."""
        done = subprocess.run(['import', '-window', 'root', path], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, universal_newlines=True, env=self.env)
        if done.returncode != 0:
            raise ViewError('import could not take the screenshot: %s' % done.stdout.strip())

    def _wait_for_robot(self, path, timeout=None):
        """Save a screenshot once the robot shows and its meshes have loaded; the Verdict.

        Raises ViewError if the robot does not show within `timeout` (default
        from tools/headless_view.yaml); the last screenshot is in `path` then.
        """
        timeout = self.settings['robot_timeout'] if timeout is None else timeout
        deadline = time.monotonic() + timeout
        previous = None
        while True:
            self._check_launch_runs('before the screenshot')
            self.capture(path)
            verdict = check_screenshot(path, self.rviz_config, self.settings)
            if (verdict.shows_robot and previous is not None and previous.shows_robot and
                    abs(verdict.robot_fraction - previous.robot_fraction) <= self.settings['stable_fraction']):
                return verdict
            if time.monotonic() > deadline:
                raise ViewError('the robot did not show in RViz within %g s (robot pixels: %.1f %% of the 3D '
                                'view, arm pixels: %d); screenshot: %s, see %s'
                                % (timeout, 100 * verdict.robot_fraction, verdict.arm_blue_pixels, path,
                                   self.log_path))
            previous = verdict
            time.sleep(self.settings['poll_interval'])

    def stop(self):
        """SIGINT to roslaunch (it stops its nodes and the master it started), then Xvfb."""
        self._stop_launch()
        if self._xvfb is not None and self._xvfb.poll() is None:
            self._xvfb.terminate()
            try:
                self._xvfb.wait(10)
            except subprocess.TimeoutExpired:
                self._xvfb.kill()
                self._xvfb.wait()
        if self._log is not None:
            self._log.close()
        self._launch = self._xvfb = self._log = None

    def _stop_launch(self):
        if self._launch is not None and self._launch.poll() is None:
            self._launch.send_signal(signal.SIGINT)
            try:
                # roslaunch gives each node 15 s after SIGINT, then SIGTERM.
                self._launch.wait(40)
            except subprocess.TimeoutExpired:
                self._launch.kill()
                self._launch.wait()
        self._launch = None


def main(argv=None):
    from ur3_ft_gripper_description.model.cli import OneLineParser
    parser = OneLineParser(
        prog='headless_view',
        description='Run the view launch under Xvfb (no display needed), move the joint sliders '
                    'beside RViz, and save a screenshot once the robot shows. Prints '
                    '"screenshot: <path>"; exit status 1 with one error line if RViz or the robot '
                    'does not show (the screenshot is saved all the same).')
    parser.add_argument('-o', '--output', required=True, help='PNG file to write')
    parser.add_argument('--log', default=os.devnull, help="file for roslaunch's and Xvfb's output")
    parser.add_argument('--robot-timeout', type=float, default=None,
                        help='seconds to wait for the robot (default: tools/headless_view.yaml)')
    parser.add_argument('launch_args', nargs='*', metavar='name:=value',
                        help='arguments of view_ur3_ft_gripper.launch')
    args = parser.parse_args(argv)
    output = os.path.abspath(args.output)
    # A terminated run still stops roslaunch and Xvfb (the with block's exit).
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    try:
        with HeadlessView(args.launch_args, args.log) as view:
            view.show(output, args.robot_timeout)
    except ViewError as e:
        print('headless_view: error: %s' % e, file=sys.stderr)
        return 1
    print('screenshot: %s' % output)
    return 0


if __name__ == '__main__':
    sys.exit(main())
