#!/usr/bin/python3
# joint_trajectory_publisher (joint_trajectory.test) on simulated time: this test publishes
# /clock at half real time and checks that every JointState is stamped with the simulated time
# and carries the script's positions at that time (linear between waypoints, a joint missing
# from a waypoint held from the one before, everything held after the last), and that each
# event's service is called once, at its scripted simulated time.
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import sys
import threading
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_srvs.srv import SetBool, SetBoolResponse, Trigger, TriggerResponse

CLOCK_START = 100.0  # s of simulated time when the test starts the clock
SIM_STEP = 0.005     # s of simulated time per clock message
WALL_STEP = 0.01     # s of wall time between clock messages: half real time


def expected(t):
    """The script of joint_trajectory.test at t seconds after its start: (a, b)."""
    if t <= 0.0:
        return 0.0, 1.0
    if t <= 2.0:
        return t / 2.0, 1.0
    if t <= 4.0:
        s = (t - 2.0) / 2.0
        return 1.0 - 2.0 * s, 1.0 + 2.0 * s
    return -1.0, 3.0


class JointTrajectoryTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.sim_time = CLOCK_START
        self.states = []  # (stamp, {name: position})
        self.calls = []   # (service, data, simulated time of the call)
        rospy.Service('/test_grasp', SetBool, self.on_grasp)
        rospy.Service('/test_reset', Trigger, self.on_reset)
        rospy.Subscriber('/joint_states', JointState, self.on_state, queue_size=1000)
        self.clock = rospy.Publisher('/clock', Clock, queue_size=10)

    def now(self):
        with self.lock:
            return self.sim_time

    def on_grasp(self, request):
        self.calls.append(('grasp', request.data, self.now()))
        return SetBoolResponse(success=True, message='ok')

    def on_reset(self, _):
        self.calls.append(('reset', None, self.now()))
        return TriggerResponse(success=True, message='ok')

    def on_state(self, msg):
        self.states.append((msg.header.stamp.to_sec(), dict(zip(msg.name, msg.position))))

    def test_follows_simulated_time(self):
        # The clock runs until the script has been over for a second of simulated time; the
        # publisher starts its script at the first clock after its services are there.
        deadline = time.time() + 40.0
        while time.time() < deadline:
            with self.lock:
                self.sim_time += SIM_STEP
                stamp = self.sim_time
            self.clock.publish(Clock(clock=rospy.Time.from_sec(stamp)))
            if self.states and stamp > self.states[0][0] + 5.0:
                break
            time.sleep(WALL_STEP)
        self.assertTrue(self.states, 'no JointState on /joint_states')
        self.assertGreater(self.now(), self.states[0][0] + 5.0, 'the script did not run through')

        # The script's start, from the first state in the first segment (a = t / 2 there).
        start = None
        for stamp, positions in self.states:
            self.assertEqual(set(positions), {'a', 'b'})
            if 0.0 < positions['a'] < 1.0 and positions['b'] == 1.0 and start is None:
                start = stamp - 2.0 * positions['a']
        self.assertIsNotNone(start, 'no state between the first two waypoints')
        self.assertGreaterEqual(start, CLOCK_START)

        # Every state: stamped in simulated time (within the clock), positions of that time.
        # Tolerance 1e-6: the stamp is the time the positions were computed for (float rounding).
        for stamp, positions in self.states:
            self.assertGreaterEqual(stamp, CLOCK_START)
            a, b = expected(stamp - start)
            self.assertAlmostEqual(positions['a'], a, delta=1e-6, msg='a at t = %.3f' % (stamp - start))
            self.assertAlmostEqual(positions['b'], b, delta=1e-6, msg='b at t = %.3f' % (stamp - start))
        # At 50 Hz of simulated time over 5 s at least, give or take the start.
        self.assertGreater(len(self.states), 200)
        self.assertLess(max(s for s, _ in self.states) - start, 6.0)

        # Each event once, in time order, at its simulated time: within two publish periods
        # (0.04 s) plus the call's own latency at half speed (well below 0.05 s).
        self.assertEqual([(c[0], c[1]) for c in self.calls], [('grasp', True), ('reset', None)])
        self.assertAlmostEqual(self.calls[0][2] - start, 1.0, delta=0.09)
        self.assertAlmostEqual(self.calls[1][2] - start, 3.0, delta=0.09)


if __name__ == '__main__':
    rospy.init_node('joint_trajectory_test')
    rostest.rosrun('pbd_cloth', 'joint_trajectory', JointTrajectoryTest, sys.argv)
