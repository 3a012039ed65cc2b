#!/usr/bin/python3
# Accuracy on demand through ROS (accuracy_target.test, scene accuracy_scene.yaml):
# - the target (0.1 % structural strain) within a budget of 3 substeps: every ~state after the
#   cloth has fallen says target_met false and target_budget_exhausted true, with substeps_run 3 and
#   the strain reached above the target; /diagnostics' simulation status is a WARN naming the
#   target, the strain reached and solver.max_substeps;
# - dynamic_reconfigure sets target 1 % and budget 400 live: the states after it meet the target,
#   with more substeps than 3, and the WARN goes away.
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import sys
import threading
import time
import unittest

import dynamic_reconfigure.client
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from pbd_cloth.msg import ClothState

NODE = '/cloth_node'


class AccuracyTargetTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.states = []
        self.statuses = []  # (level, message) of the simulation status, in order
        rospy.Subscriber(NODE + '/state', ClothState, self.on_state, queue_size=100)
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=10)

    def on_state(self, msg):
        with self.lock:
            self.states.append(msg)

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                if status.name.endswith('simulation'):
                    self.statuses.append((status.level, status.message))

    def wait_for(self, condition, timeout, what):
        deadline = time.time() + timeout
        while time.time() < deadline and not rospy.is_shutdown():
            with self.lock:
                if condition():
                    return
            time.sleep(0.05)
        self.fail('timed out waiting for ' + what)

    def test_budget_then_live_target(self):
        # The cloth falls and stretches within its first half second of simulated time.
        self.wait_for(lambda: any(s.stats.sim_time > 1.0 for s in self.states), 30.0,
                      '1 s of simulated time')
        with self.lock:
            late = [s.stats for s in self.states if s.stats.sim_time > 0.5]
        self.assertTrue(late)
        for stats in late:
            self.assertAlmostEqual(stats.target_max_strain, 0.001)
            self.assertFalse(stats.target_met)
            self.assertTrue(stats.target_budget_exhausted)
            self.assertEqual(stats.substeps_run, 3)
            self.assertGreater(stats.structural_max_strain, 0.001)
        self.wait_for(lambda: any(level == DiagnosticStatus.WARN and 'max_substeps 3' in message
                                  for level, message in self.statuses), 10.0,
                      'the WARN of a target the budget cannot meet')
        with self.lock:
            warn = [m for level, m in self.statuses if level == DiagnosticStatus.WARN][-1]
        self.assertIn('target max strain 0.1 %', warn)
        self.assertIn('reached', warn)

        client = dynamic_reconfigure.client.Client(NODE, timeout=30.0)
        client.update_configuration({'target_max_strain': 0.01, 'max_substeps': 400})
        with self.lock:
            changed_at = self.states[-1].stats.sim_time
        self.wait_for(lambda: any(s.stats.sim_time > changed_at + 1.0 for s in self.states), 30.0,
                      '1 s of simulated time after the change')
        with self.lock:
            after = [s.stats for s in self.states if s.stats.sim_time > changed_at + 0.5]
            self.statuses.clear()
        self.assertTrue(after)
        for stats in after:
            self.assertAlmostEqual(stats.target_max_strain, 0.01)
            self.assertTrue(stats.target_met, 'strain %g' % stats.structural_max_strain)
            self.assertLessEqual(stats.structural_max_strain, 0.01)
            self.assertFalse(stats.target_budget_exhausted)
        self.assertGreater(max(s.substeps_run for s in after), 3)
        self.wait_for(lambda: len(self.statuses) > 0, 10.0, 'a simulation status after the change')
        with self.lock:
            self.assertNotIn('max_substeps', self.statuses[-1][1])


if __name__ == '__main__':
    rospy.init_node('accuracy_target_test')
    rostest.rosrun('pbd_cloth', 'accuracy_target', AccuracyTargetTest, sys.argv)
