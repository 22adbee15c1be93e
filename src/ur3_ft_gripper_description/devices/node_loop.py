"""What every simulated-device node does around its own work: loop or spin, and a master restart.

rospy registers a node's topics and services with the master once, at
start-up. A restarted master knows nothing of them, so new subscribers would
never find the node while it runs on. rospy offers no public way to register
again, so the node does what ROS users expect instead: it notices the new
master (its process id, from the master API, changes), says so in one line
and exits; the launch files declare the nodes respawn="true", and roslaunch
starts them again on the new master.
"""

import gc
import os
import sys
import threading
import warnings
import xmlrpc.client

# The clock loop's niceness at real_time_factor 0 (see run_as_clock).
FULL_SPEED_NICENESS = 5
# Seconds between two looks at the master.
MASTER_CHECK_PERIOD = 1.0

# What a call to a master that is not (yet, or no longer) there raises.
MASTER_UNREACHABLE = (OSError, xmlrpc.client.Error)


def main(name, run):
    """A device node's main(): init `name` once the master answers, `run(rospy)`; the exit status.

    rospy, unlike roscpp, does not wait for the master: a node that roslaunch
    respawns while a restarted master is still coming up would die in its
    first parameter read. It waits, saying so once; a master lost during
    start-up ends it with one line (and roslaunch's respawn tries again).
    """
    import rosgraph
    import rospy
    said = False
    pause = threading.Event()
    while not rosgraph.is_master_online():
        if not said:
            print('%s: waiting for the ROS master at %s' % (name, rosgraph.get_master_uri()),
                  file=sys.stderr)
            said = True
        pause.wait(0.5)
    rospy.init_node(name)
    try:
        return run(rospy)
    except MASTER_UNREACHABLE as exc:
        print('%s: lost the ROS master at %s (%s): exiting' % (name, rosgraph.get_master_uri(), exc),
              file=sys.stderr)
        return 1


class PublishGate(object):
    """Work that publishes goes through here, and none runs once rospy starts closing topics.

    rospy closes every topic in a pre-shutdown hook and only then says
    is_shutdown(); a publish() in between raises "publish() to a closed topic".
    Client shutdown hooks run before that hook: this one closes the gate, under
    the lock the work holds, so work in progress ends first and none starts
    after. The lock is re-entrant because a signal handler (Ctrl-C) runs the
    hooks in the thread that may hold it.
    """

    def __init__(self, rospy):
        self._lock = threading.RLock()
        self._open = True
        rospy.on_shutdown(self._close)

    def _close(self):
        with self._lock:
            self._open = False

    def call(self, work, *args):
        """work(*args) while the node runs; its result, or None once shutdown has begun."""
        with self._lock:
            if self._open:
                return work(*args)
        return None


def watch_master(rospy, period=MASTER_CHECK_PERIOD):
    """Shut this node down with one fatal line when the master is restarted.

    Returns a dict whose 'restarted' turns True then; a daemon thread polls.
    """
    import rosgraph
    name = rospy.get_name()
    master = rosgraph.Master(name)
    first = master.getPid()
    state = {'restarted': False}
    unreachable = MASTER_UNREACHABLE + (rosgraph.MasterException,)

    def loop():
        # Wall-clock waits: with use_sim_time and no clock, rospy.sleep would block forever.
        pause = threading.Event()
        while not rospy.is_shutdown():
            pause.wait(period)
            try:
                pid = master.getPid()
            except unreachable:
                continue  # gone for now: existing connections keep working meanwhile
            if pid != first:
                state['restarted'] = True
                rospy.logfatal('%s: the ROS master at %s was restarted and does not know this node: '
                               'exiting (launch files start it again with respawn="true")'
                               % (name, master.master_uri))
                rospy.signal_shutdown('ROS master restarted')
                return

    threading.Thread(target=loop, name='watch_master', daemon=True).start()
    return state


def run_at_rate(rospy, hz, step, on_time_jump=None):
    """Call `step()` `hz` times a second until rospy shuts down; returns the exit status.

    Calls `on_time_jump()` when ROS time jumps back (a bag or simulation restarted).
    No `step()` runs once shutdown has begun (PublishGate).
    """
    master = watch_master(rospy)
    gate = PublishGate(rospy)
    # Everything made so far (modules, message classes, the model) lives as long as
    # the node: out of the collector's reach, a full collection no longer stops
    # the loop for ~20 ms (more on a loaded machine), which showed as message gaps.
    gc.freeze()
    rate = rospy.Rate(hz)
    while not rospy.is_shutdown():
        gate.call(step)
        try:
            rate.sleep()
        except rospy.ROSTimeMovedBackwardsException:
            if on_time_jump is not None:
                on_time_jump()
        except rospy.ROSInterruptException:
            break
    return 1 if master['restarted'] else 0


def run_on_every_tick(rospy, hz, step, on_time_jump=None, max_backlog=None):
    """Call `step(stamp)` once for every tick of 1/`hz` s of ROS time until rospy shuts down; the exit status.

    A tick that passed while the node ran late (the cell runs faster than
    real time, the machine is busy) is still served, late, with its own time
    as `stamp` (a rospy.Time, a whole number of periods), so that over any
    stretch of time the node publishes exactly `hz` messages a second, as a
    device streaming from its own clock does: a real unit's samples wait in
    the serial line's buffer for a late driver. rospy.Rate would drop them
    instead. On the simulated clock (`max_backlog` None) every tick is
    served; on the wall clock at most the last `max_backlog`, so that a
    machine that slept does not replay the night. A clock that jumps back
    (the simulation restarted) starts the ticks anew and calls
    `on_time_jump()`.
    """
    master = watch_master(rospy)
    gate = PublishGate(rospy)
    gc.freeze()
    period_ns = int(round(1e9 / hz))
    tick = None  # the number of the last tick served
    while not rospy.is_shutdown():
        now = rospy.Time.now()
        due = now.to_nsec() // period_ns
        if tick is not None and due < tick and on_time_jump is not None:
            on_time_jump()
        if tick is None or due < tick:
            tick = due - 1
        if max_backlog is not None:
            tick = max(tick, due - max_backlog)
        while tick < due and not rospy.is_shutdown():
            tick += 1
            gate.call(step, rospy.Time(*divmod(tick * period_ns, 1000000000)))
        try:
            # Until the next tick from the time now, after serving: a long burst is not slept again.
            rospy.sleep(rospy.Time(*divmod((tick + 1) * period_ns, 1000000000)) - rospy.Time.now())
        except rospy.ROSTimeMovedBackwardsException:
            tick = None
            if on_time_jump is not None:
                on_time_jump()
        except rospy.ROSInterruptException:
            break
    return 1 if master['restarted'] else 0


def other_clock_publishers(rospy):
    """The nodes other than this one that publish /clock (the master's view)."""
    import rosgraph
    publishers = rosgraph.Master(rospy.get_name()).getSystemState()[0]
    me = rospy.get_name()
    return sorted(node for topic, nodes in publishers if topic == '/clock' for node in nodes if node != me)


def _rival_clock_line(rospy, rivals):
    return ('%s: %s publish%s /clock too, and this node is the simulated cell\'s clock (use_sim_time:=true): '
            'stop %s, or start the cell with use_sim_time:=false' % (
                rospy.get_name(), ', '.join(rivals), 'es' if len(rivals) == 1 else '',
                'it' if len(rivals) == 1 else 'them'))


def cycle_publisher(rospy, topic, message_class, queue_size, on_sim_clock):
    """The publisher of a stream the control cycle sends every period, each message of which counts.

    On the simulated clock it writes to each subscriber's socket in the
    publishing thread (rospy's queue_size=None). rospy's queued publisher
    hands each message to a thread per subscriber and yields the processor
    to it, and those hand-offs, every period, cost the cycle about as much as
    its physics. A subscriber that stops reading then holds the cycle, and
    with it the simulated clock of every node, once its socket's buffer is
    full; on the wall clock (`on_sim_clock` False) that would make the cell
    miss its periods, so there the publisher keeps rospy's queue of
    `queue_size`.
    """
    if not on_sim_clock:
        return rospy.Publisher(topic, message_class, queue_size=queue_size)
    with warnings.catch_warnings():  # rospy warns of queue_size=None, its old default, as of a mistake
        warnings.simplefilter('ignore')
        return rospy.Publisher(topic, message_class, queue_size=None)


def run_as_clock(rospy, clock, step, check_period=2.0):
    """The simulated cell's clock loop: per cycle, `clock.tick()`, /clock (on the cycles `clock.published` names),
    `step(period, stamp)`, the pace's wait.

    `clock` is a sim_clock.SimClock; `stamp` is the cycle's simulated time as a rospy.Time, which
    everything the cycle publishes carries. Another node publishing /clock (a bag played with --clock,
    Gazebo) stops this one with one fatal line naming it: two clocks would make every node's time jump.
    Returns the exit status.
    """
    import rosgraph
    from rosgraph_msgs.msg import Clock
    master = watch_master(rospy)
    gate = PublishGate(rospy)
    # Queued, unlike the cycle's streams: a subscriber that falls behind then skips ticks (rospy drops the
    # oldest of a connection's queue) and its ROS time stays the cell's; written directly, every tick
    # would wait in its socket, and its clock would lag ever further behind.
    publisher = rospy.Publisher('/clock', Clock, queue_size=10)
    unreachable = MASTER_UNREACHABLE + (rosgraph.MasterException,)
    rivals = other_clock_publishers(rospy)
    if rivals:
        rospy.logfatal(_rival_clock_line(rospy, rivals))
        # rospy's own threads (actionlib's, the servers') would keep the process alive past main's return.
        rospy.signal_shutdown('another /clock')
        return 1
    found = []

    def watch_rivals():
        pause = threading.Event()
        while not rospy.is_shutdown() and not found:
            pause.wait(check_period)
            try:
                others = other_clock_publishers(rospy)
            except unreachable:
                continue
            if others:
                found.append(others)
                rospy.logfatal(_rival_clock_line(rospy, others))
                rospy.signal_shutdown('another /clock')

    threading.Thread(target=watch_rivals, name='watch /clock', daemon=True).start()
    gc.freeze()
    message = Clock()
    pause = threading.Event()  # wall-clock waits: the pace is the wall clock's

    def cycle():
        message.clock = rospy.Time(*divmod(clock.nanoseconds, 1000000000))
        if clock.published:
            publisher.publish(message)
        step(clock.period, message.clock)
        return True

    if clock.factor == 0.0:
        # As fast as the machine allows, the clock takes the processor the cell's other nodes leave: they
        # work when it moves on, and a clock that took the processor from them would run ahead of them
        # (a relay's stamps late, a slow node's time behind), so it yields to them.
        os.nice(FULL_SPEED_NICENESS)
    clock.start()
    while not rospy.is_shutdown():
        clock.tick()
        if not gate.call(cycle):
            break
        wait = clock.pause()
        if wait > 0.0:
            pause.wait(wait)
    return 1 if master['restarted'] or found else 0


def spin(rospy):
    """rospy.spin() for a callback-only node, with the master watch; returns the exit status.

    Callbacks that publish do so through a PublishGate made before they subscribe.
    """
    master = watch_master(rospy)
    gc.freeze()
    rospy.spin()
    return 1 if master['restarted'] else 0


def wait_for_param(rospy, name, warning, quiet=1.0, poll=0.2):
    """The value of parameter `name` once it is set (None on shutdown); warns once after `quiet` s."""
    pause = threading.Event()
    waited = 0.0
    while not rospy.is_shutdown():
        if rospy.has_param(name):
            return rospy.get_param(name)
        if waited < quiet <= waited + poll:
            rospy.logwarn(warning)
        waited += poll
        pause.wait(poll)
    return None
