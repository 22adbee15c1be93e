"""Keeps a rospy node reachable across a restart of the ROS master.

rospy registers a node's topics and services with the master once, at
start-up (rospy.impl.registration.RegManager.start). Connections made before
a master restart keep working, but the new master knows nothing of the node,
so a subscriber started afterwards never finds it: the node looks dead while
it runs. The watch asks the master every `period` seconds whether it knows
this node (master API ``lookupNode``) and:

* master unreachable: warns once; the node goes on serving the connections
  it has;
* master reachable and knows the node: nothing to do (after an outage it says
  once that the master is back);
* master reachable and does not know the node (it was restarted): registers
  the node's publications, subscriptions and services again through the
  master API and says so once; if that fails, logs one fatal line naming the
  fix and shuts the node down with exit status 1.

Parameters the node read at start-up stay in effect; the new master's
parameter server starts empty, which only matters to nodes started later.
"""

import socket
import threading
import xmlrpc.client


class MasterWatch(object):
    """The state machine; `master` is a rosgraph.Master, `register_all` re-registers the node."""

    def __init__(self, name, master, register_all, log_warn, log_info, log_fatal, shutdown):
        self.name = name
        self.state = 'ok'
        self.exit_status = 0
        self._master = master
        self._register_all = register_all
        self._warn, self._info, self._fatal = log_warn, log_info, log_fatal
        self._shutdown = shutdown

    def check(self, own_uri):
        """One look at the master; returns the state: 'ok', 'unreachable' or 'failed'."""
        import rosgraph
        if self.state == 'failed':
            return self.state
        try:
            known = self._master.lookupNode(self.name) == own_uri
        except rosgraph.MasterError:
            known = False  # "unknown node": a master that never heard of us
        except (OSError, socket.error, xmlrpc.client.Error, rosgraph.MasterException) as exc:
            if self.state != 'unreachable':
                self.state = 'unreachable'
                self._warn('%s: the ROS master at %s is unreachable (%s); still serving existing '
                           'connections, re-registering when it is back'
                           % (self.name, self._master.master_uri, exc))
            return self.state
        if known:
            if self.state == 'unreachable':
                self._info('%s: the ROS master at %s is reachable again' % (
                    self.name, self._master.master_uri))
            self.state = 'ok'
            return self.state
        try:
            count = self._register_all()
        except Exception as exc:  # any failure here ends in the same clear exit
            self.state = 'failed'
            self.exit_status = 1
            self._fatal('%s: the ROS master at %s was restarted and re-registering with it failed '
                        '(%s): exiting; start the node again' % (
                            self.name, self._master.master_uri, exc))
            self._shutdown('master restarted, re-registration failed')
            return self.state
        self.state = 'ok'
        self._info('%s: the ROS master at %s was restarted; registered this node\'s %d topics and '
                   'services with it again' % (self.name, self._master.master_uri, count))
        return self.state


def register_all(master, node_uri):
    """Register every publication, subscription and service of this rospy node with `master`."""
    from rospy.impl.registration import get_service_manager, get_topic_manager
    topics, services = get_topic_manager(), get_service_manager()
    count = 0
    for name, data_type in topics.get_publications():
        master.registerPublisher(name, data_type, node_uri)
        count += 1
    node = xmlrpc.client.ServerProxy(node_uri)
    for name, data_type in topics.get_subscriptions():
        publishers = master.registerSubscriber(name, data_type, node_uri)
        # What the master would send a subscriber on a new publisher (slave API).
        node.publisherUpdate('/master', name, publishers)
        count += 1
    for name, service_uri in services.get_services():
        master.registerService(name, service_uri, node_uri)
        count += 1
    return count


def start(rospy, period=1.0):
    """Watch the master from a daemon thread of this rospy node; returns the MasterWatch."""
    import rosgraph
    name = rospy.get_name()
    master = rosgraph.Master(name)
    watch = MasterWatch(name, master, lambda: register_all(master, rospy.get_node_uri()),
                        rospy.logwarn, rospy.loginfo, rospy.logfatal, rospy.signal_shutdown)

    def loop():
        while not rospy.is_shutdown() and watch.check(rospy.get_node_uri()) != 'failed':
            # Wall-clock wait: with use_sim_time and no clock, rospy.sleep would block forever.
            threading.Event().wait(period)

    threading.Thread(target=loop, name='master_watch', daemon=True).start()
    return watch
