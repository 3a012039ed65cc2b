#!/usr/bin/python3
# Faults (faults.test, scene interaction_scene.yaml, the node with ~fault_injection on):
# - a NaN injected inside a step: no ~state ever carries a non-finite value, stats.restored_steps
#   counts the undone step, /diagnostics reports it as an ERROR naming the particle, and the
#   simulation goes on (simulated time advances, the grasped corner still follows its gripper);
# - the same for an energy blow-up (a particle far faster than solver.max_speed);
# - a fault name the hook does not know is a rejected input, not a fault;
# - the tf broadcaster of the `follower` gripper (frame `hand`) dies while it holds the cloth:
#   the gripper stays where the last transform put it, the corner stays held there, and the
#   outage is one rejected input (tf failure) with a warning on /rosout naming the frame.
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TransformStamped
from pbd_cloth.msg import ClothState
from pbd_cloth.srv import GetState
from rosgraph_msgs.msg import Log
from std_msgs.msg import String
from std_srvs.srv import SetBool

NODE = '/cloth_node'
CORNER = 90  # the bottom-left corner of the hanging 10 x 10 cloth, at (0, 0, 0.55)


def finite(state):
    return all(math.isfinite(v) for p in state.positions for v in (p.x, p.y, p.z)) and \
        all(math.isfinite(v) for p in state.velocities for v in (p.x, p.y, p.z))


class FaultsTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.states = []
        self.non_finite = 0
        self.errors = []     # summaries of ERROR simulation statuses
        self.warnings = []   # /rosout warnings of the node
        rospy.Subscriber(NODE + '/state', ClothState, self.on_state, queue_size=100)
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=10)
        rospy.Subscriber('/rosout', Log, self.on_log, queue_size=100)
        self.inject = rospy.Publisher(NODE + '/inject_fault', String, queue_size=10)
        self.broadcaster = tf2_ros.TransformBroadcaster()
        self.hand = None  # (x, y, z) broadcast while not None
        self.broadcasting = True
        self.tf_thread = threading.Thread(target=self.broadcast, daemon=True)
        self.tf_thread.start()
        rospy.wait_for_service(NODE + '/get_state', timeout=30.0)
        self.get_state = rospy.ServiceProxy(NODE + '/get_state', GetState)

    def tearDown(self):
        self.broadcasting = False

    def on_state(self, msg):
        with self.lock:
            self.states.append(msg)
            if not finite(msg):
                self.non_finite += 1

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                if status.name.endswith('simulation') and status.level == DiagnosticStatus.ERROR:
                    self.errors.append(status.message)

    def on_log(self, msg):
        if msg.level == Log.WARN and msg.name == NODE:
            with self.lock:
                self.warnings.append(msg.msg)

    def broadcast(self):
        rate = rospy.Rate(30.0)
        while self.broadcasting and not rospy.is_shutdown():
            hand = self.hand
            if hand is not None:
                t = TransformStamped()
                t.header.stamp = rospy.Time.now()
                t.header.frame_id = 'world'
                t.child_frame_id = 'hand'
                t.transform.translation.x, t.transform.translation.y, \
                    t.transform.translation.z = hand
                t.transform.rotation.w = 1.0
                self.broadcaster.sendTransform(t)
            try:
                rate.sleep()
            except rospy.ROSInterruptException:
                return

    def latest(self):
        with self.lock:
            return self.states[-1] if self.states else None

    def wait_for(self, condition, what, timeout=15.0):
        deadline = time.time() + timeout
        while time.time() < deadline and not rospy.is_shutdown():
            state = self.latest()
            if state is not None and condition(state):
                return state
            time.sleep(0.05)
        self.fail('timed out waiting for ' + what)

    def follower(self):
        state = self.get_state().state
        return next(g for g in state.grippers if g.name == 'follower')

    def test_faults(self):
        self.wait_for(lambda s: s.stats.sim_time > 0.5, 'the first states')

        # The follower (frame `hand`) takes the bottom-left corner and lifts it 10 cm.
        self.hand = (0.0, 0.0, 0.55)
        self.wait_for(lambda s: True, 'tf', 1.0)
        time.sleep(1.0)
        grasp = rospy.ServiceProxy(NODE + '/follower/grasp', SetBool)
        self.assertTrue(grasp(True).success)
        for k in range(1, 21):
            self.hand = (0.0, 0.0, 0.55 + 0.005 * k)
            time.sleep(0.05)
        lifted = self.wait_for(
            lambda s: CORNER in s.kinematic and abs(s.positions[CORNER].z - 0.65) < 2e-3,
            'the corner lifted to 0.65 m')
        # The cloth below still swings into its new rest (damping 1/s): 3 s of simulated time
        # leave e^-3 of that motion, so what the faults below must not change is a state at rest
        # (on a fresh clone's sanitizer run, comparing with the state at the end of the lift
        # failed at 5.7 cm of that settling).
        held = self.wait_for(lambda s: s.stats.sim_time > lifted.stats.sim_time + 3.0,
                             'the lifted cloth to settle')
        self.assertEqual(self.non_finite, 0)

        # Faults inside the step, each undone; the corner stays with the gripper throughout.
        for fault, count in (('nan', 1), ('blowup', 2)):
            before = self.latest().stats.sim_time
            self.inject.publish(String(data=fault))
            state = self.wait_for(lambda s: s.stats.restored_steps >= count,
                                  'the %s step undone' % fault)
            self.assertEqual(state.stats.restored_steps, count)
            later = self.wait_for(lambda s: s.stats.sim_time > state.stats.sim_time + 0.5,
                                  'the simulation to go on after the %s' % fault)
            self.assertGreater(later.stats.sim_time, before)
            self.assertIn(CORNER, later.kinematic)
            self.assertAlmostEqual(later.positions[CORNER].z, 0.65, delta=2e-3)
            # The cloth goes on from where it was: no particle thrown away (the undone step's
            # NaN or speed went nowhere), the strain as before the fault.
            moved = max(((a.x - b.x) ** 2 + (a.y - b.y) ** 2 + (a.z - b.z) ** 2) ** 0.5
                        for a, b in zip(later.positions, held.positions))
            self.assertLess(moved, 0.05)
            self.assertLess(later.stats.max_strain, held.stats.max_strain + 0.02)
        self.assertEqual(self.non_finite, 0, 'a non-finite state was published')
        deadline = time.time() + 5.0
        while time.time() < deadline and len(self.errors) < 2:
            time.sleep(0.1)
        with self.lock:
            errors = list(self.errors)
        self.assertTrue(any('not finite' in e and 'undone' in e for e in errors), errors)
        self.assertTrue(any('solver.max_speed' in e for e in errors), errors)

        # An unknown fault name is a rejected input.
        rejected = self.latest().stats.rejected_inputs
        self.inject.publish(String(data='meteor'))
        self.wait_for(lambda s: s.stats.rejected_inputs == rejected + 1, 'the unknown fault refused')
        self.assertEqual(self.latest().stats.restored_steps, 2)

        # The tf broadcaster dies while the gripper holds the corner.
        rejected = self.latest().stats.rejected_inputs
        self.hand = None
        pose_before = self.follower().pose.position
        time.sleep(3.0)  # ~body_tf_timeout is 0.5 s
        after = self.follower()
        self.assertAlmostEqual(after.pose.position.z, pose_before.z, delta=1e-3)
        self.assertAlmostEqual(after.pose.position.z, 0.65, delta=2e-3)
        self.assertEqual(list(after.grasped), [CORNER])
        state = self.latest()
        self.assertIn(CORNER, state.kinematic)
        self.assertAlmostEqual(state.positions[CORNER].z, 0.65, delta=2e-3)
        self.assertEqual(state.stats.rejected_inputs, rejected + 1,
                         'the outage is one rejected input')
        with self.lock:
            warnings = list(self.warnings)
        self.assertTrue(any("'hand'" in w and 'stays where it is' in w for w in warnings),
                        warnings[-5:])
        self.assertEqual(self.non_finite, 0)


if __name__ == '__main__':
    rospy.init_node('faults_test')
    rostest.rosrun('pbd_cloth', 'faults', FaultsTest, sys.argv)
