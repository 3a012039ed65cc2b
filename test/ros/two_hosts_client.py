#!/usr/bin/python3
# The client half of scripts/run_two_hosts: runs in the network namespace of the second "host"
# (ROS_IP and ROS_MASTER_URI set by the script) and drives cloth_node on the first across the veth
# pair: the state arrives (node -> client), a gripper pose reaches the node (client -> node), a
# grasp takes the corner it is on and drags it, a release lets it go. Exit status 0 when every
# check holds; each failed check is printed.
#
# The scene is test/ros/interaction_scene.yaml: a 10 x 10 cloth (0.05 m) hanging from particles
# 0 and 9, row 0 at z = 1; gripper `left` (radius 0.06).
import sys
import time

import rospy
from geometry_msgs.msg import PoseStamped
from pbd_cloth.msg import ClothState
from std_srvs.srv import SetBool

NODE = '/cloth_node'


class Client:
    def __init__(self):
        self.state = None
        rospy.Subscriber(NODE + '/state', ClothState, self.on_state, queue_size=1)
        self.pose = rospy.Publisher(NODE + '/left/pose', PoseStamped, queue_size=10)
        self.failures = []

    def on_state(self, msg):
        self.state = msg

    def check(self, ok, what):
        print('%s: %s' % ('ok  ' if ok else 'FAIL', what))
        if not ok:
            self.failures.append(what)
        return ok

    def wait_state(self, predicate, timeout):
        deadline = time.time() + timeout
        while time.time() < deadline and not rospy.is_shutdown():
            state = self.state
            if state is not None and predicate(state):
                return state
            time.sleep(0.05)
        return None

    def send_pose(self, x, y, z):
        msg = PoseStamped()
        msg.header.frame_id = 'world'
        msg.header.stamp = rospy.Time.now()
        msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = x, y, z
        msg.pose.orientation.w = 1.0
        self.pose.publish(msg)

    def hold_pose(self, x, y, z, seconds):
        end = time.time() + seconds
        while time.time() < end:
            self.send_pose(x, y, z)
            time.sleep(0.05)

    def run(self):
        first = self.wait_state(lambda s: len(s.positions) == 100, 30.0)
        if not self.check(first is not None, 'the state arrives from the other host'):
            return
        # The bottom-left corner (particle 90) where the cloth hangs now.
        corner = first.positions[90]
        deadline = time.time() + 10.0
        while self.pose.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.05)
        self.check(self.pose.get_num_connections() > 0,
                   'the node on the other host subscribes to ~left/pose')
        self.hold_pose(corner.x, corner.y, corner.z, 1.0)
        rospy.wait_for_service(NODE + '/left/grasp', timeout=10.0)
        grasp = rospy.ServiceProxy(NODE + '/left/grasp', SetBool)
        reply = grasp(True)
        self.check(reply.success, 'grasp across hosts: %s' % reply.message)
        held = self.wait_state(lambda s: 90 in s.kinematic, 5.0)
        self.check(held is not None, 'the corner is held (kinematic) in the state')
        # Drag it 0.3 m along -y: the state shows the corner following.
        self.hold_pose(corner.x, corner.y - 0.3, corner.z, 2.0)
        moved = self.wait_state(lambda s: abs(s.positions[90].y - (corner.y - 0.3)) < 0.02, 5.0)
        self.check(moved is not None, 'the dragged corner follows the pose sent from this host')
        reply = grasp(False)
        self.check(reply.success, 'release across hosts: %s' % reply.message)
        released = self.wait_state(lambda s: 90 not in s.kinematic, 5.0)
        self.check(released is not None, 'the corner is released')
        swung = self.wait_state(lambda s: abs(s.positions[90].y - (corner.y - 0.3)) > 0.05, 5.0)
        self.check(swung is not None, 'the released corner swings back')


def main():
    rospy.init_node('two_hosts_client')
    client = Client()
    try:
        client.run()
    except Exception as error:  # a service that never appears, a dead connection
        client.check(False, 'unexpected %s: %s' % (type(error).__name__, error))
    return 1 if client.failures else 0


if __name__ == '__main__':
    sys.exit(main())
