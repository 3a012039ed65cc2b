#!/usr/bin/python3
# solver.adaptive_threads through the node (adaptive_threads.test): the simulation status of
# /diagnostics carries the count of steps run on the calling thread alone since the last report.
# The node with the choice on (solver.threads 2) reports some: its first probe, a few steps after
# the start, runs on the calling thread whatever the times. The node with it off reports 0 in
# every report. Both report steps, so both keep stepping. Neither reports particles held straight
# (solver.taut_chains left the product on 2026-12-07, and its line of the status with it).
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import sys
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray

KEY = 'steps on the calling thread alone (since last report; solver.adaptive_threads)'
HELD_KEY = 'particles held straight (last step; solver.taut_chains)'


class AdaptiveThreadsTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        # (one-thread steps, steps, the removed taut-chain line present) per report
        self.reports = {'cloth_adaptive': [], 'cloth_fixed': []}
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=20)

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                # Status names: '<node's namespace>: simulation', e.g. '/cloth_fixed: simulation'.
                node = status.name.split(':')[0].strip('/')
                if node not in self.reports or not status.name.endswith('simulation'):
                    continue
                values = {kv.key: kv.value for kv in status.values}
                # A missing key fails the test below (-1 steps), not this callback, whose
                # exceptions rospy only logs.
                self.reports[node].append((int(values.get(KEY, -1)),
                                           int(values.get('steps since last report', -1)),
                                           HELD_KEY in values))

    def test_the_adaptive_node_counts_its_one_thread_steps(self):
        deadline = time.time() + 30.0
        while time.time() < deadline:
            with self.lock:
                adaptive = list(self.reports['cloth_adaptive'])
                fixed = list(self.reports['cloth_fixed'])
            if sum(r[0] for r in adaptive) > 0 and len(fixed) >= 3 and len(adaptive) >= 3:
                break
            time.sleep(0.2)
        self.assertGreater(sum(r[0] for r in adaptive), 0, adaptive)
        self.assertGreaterEqual(len(fixed), 3, fixed)
        self.assertEqual(sum(r[0] for r in fixed), 0, fixed)
        # Both step: every report after the first counts steps, and never more on one thread
        # than it ran.
        for node, reports in (('cloth_adaptive', adaptive), ('cloth_fixed', fixed)):
            self.assertGreater(sum(r[1] for r in reports[1:]), 0, node)
            for solo, steps, _ in reports:
                self.assertGreaterEqual(solo, 0, (node, KEY, reports))
                self.assertLessEqual(solo, steps, node)
            # No report carries the line of the removed solver.taut_chains.
            for _, _, held in reports:
                self.assertFalse(held, (node, HELD_KEY, reports))


if __name__ == '__main__':
    rospy.init_node('adaptive_threads_test')
    rostest.rosrun('pbd_cloth', 'adaptive_threads', AdaptiveThreadsTest, sys.argv)
