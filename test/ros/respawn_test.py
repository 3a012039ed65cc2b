#!/usr/bin/python3
# respawn.test: the `left` gripper takes the bottom-left corner of the hanging cloth
# (interaction_scene.yaml) and lifts it 20 cm; the node is then killed with SIGKILL (no chance to
# clean up) and roslaunch respawns it. The first state of the new process: simulated time under
# 1 s, only the two pinned corners kinematic, and every particle within 5 mm of where the scene
# puts it (the cloth hangs at rest from the start), while before the kill the corner was 20 cm off.
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import os
import signal
import sys
import threading
import time
import unittest
import xmlrpc.client

import rosgraph
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from pbd_cloth.msg import ClothState
from std_srvs.srv import SetBool

NODE = '/cloth_node'
CORNER = 90  # bottom-left corner: (0, 0, 0.55)


def scene_position(index):
    """Where interaction_scene.yaml puts particle `index`: rows down from z = 1 in the x-z plane."""
    row, col = divmod(index, 10)
    return (0.05 * col, 0.0, 1.0 - 0.05 * row)


class RespawnTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.states = []
        rospy.Subscriber(NODE + '/state', ClothState, self.on_state, queue_size=100)
        self.pose = rospy.Publisher(NODE + '/left/pose', PoseStamped, queue_size=10)

    def on_state(self, msg):
        with self.lock:
            self.states.append(msg)

    def wait_for(self, condition, what, timeout=20.0):
        deadline = time.time() + timeout
        while time.time() < deadline and not rospy.is_shutdown():
            with self.lock:
                found = [s for s in self.states if condition(s)]
            if found:
                return found[0]
            time.sleep(0.05)
        self.fail('timed out waiting for ' + what)

    def send_pose(self, z):
        msg = PoseStamped()
        msg.header.stamp = rospy.Time.now()
        msg.header.frame_id = 'world'
        msg.pose.position.z = z
        msg.pose.orientation.w = 1.0
        self.pose.publish(msg)

    def node_pid(self):
        uri = rosgraph.Master('/respawn_test').lookupNode(NODE)
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid('/respawn_test')
        self.assertEqual(code, 1)
        return pid

    def test_respawn(self):
        self.wait_for(lambda s: s.stats.sim_time > 0.5, 'the first states')
        rospy.wait_for_service(NODE + '/left/grasp', timeout=10.0)
        for _ in range(5):
            self.send_pose(0.55)
            time.sleep(0.1)
        self.assertTrue(rospy.ServiceProxy(NODE + '/left/grasp', SetBool)(True).success)
        for k in range(1, 21):
            self.send_pose(0.55 + 0.01 * k)
            time.sleep(0.05)
        lifted = self.wait_for(lambda s: CORNER in s.kinematic and s.positions[CORNER].z > 0.74,
                               'the corner lifted')
        pid = self.node_pid()

        os.kill(pid, signal.SIGKILL)
        killed_at = lifted.stats.sim_time
        with self.lock:
            self.states = []
        # The new process's first state: its simulated time starts again from 0.
        first = self.wait_for(lambda s: s.stats.sim_time < killed_at, 'the respawned node',
                              timeout=40.0)
        deadline = time.time() + 10.0
        while time.time() < deadline:  # the master may still name the killed process's URI
            try:
                if self.node_pid() != pid:
                    break
            except (OSError, rosgraph.MasterError):
                pass
            time.sleep(0.2)
        self.assertNotEqual(self.node_pid(), pid, 'the node was not respawned')
        self.assertLess(first.stats.sim_time, 1.0)
        self.assertEqual(sorted(first.kinematic), [0, 9])
        for i, p in enumerate(first.positions):
            x, y, z = scene_position(i)
            distance = ((p.x - x) ** 2 + (p.y - y) ** 2 + (p.z - z) ** 2) ** 0.5
            self.assertLess(distance, 5e-3, 'particle %d is %.3f m from its start' % (i, distance))
        self.assertEqual(first.stats.rejected_inputs, 0)


if __name__ == '__main__':
    rospy.init_node('respawn_test')
    rostest.rosrun('pbd_cloth', 'respawn', RespawnTest, sys.argv)
