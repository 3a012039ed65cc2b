#!/usr/bin/python3
# cloth_node with an invalid scene (config_error.test sets one key out of range) must stop at
# start-up: exit non-zero, say which key is wrong, and never advertise ~state.
import subprocess
import sys
import unittest

import rosgraph
import roslib.packages
import rospy
import rostest


class ConfigErrorTest(unittest.TestCase):
    def test_invalid_scene_stops_startup(self):
        name = rospy.get_param('~node_name')
        bad_key = rospy.get_param('~bad_key')
        nodes = roslib.packages.find_node('pbd_cloth', 'cloth_node')
        self.assertTrue(nodes, 'cloth_node executable not found')

        try:
            result = subprocess.run([nodes[0], '__name:=' + name], stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, timeout=30.0)
        except subprocess.TimeoutExpired:
            self.fail('cloth_node kept running with an invalid %s' % bad_key)
        output = result.stdout.decode('utf-8', 'replace')
        sys.stdout.write(output)

        self.assertNotEqual(result.returncode, 0, 'cloth_node exited 0 with an invalid scene')
        self.assertIn(bad_key, output, 'the error message does not name the bad key')
        self.assertIn('FATAL', output)
        topics = [t for t, _ in rosgraph.Master('/config_error_test').getPublishedTopics('')]
        self.assertNotIn('/%s/state' % name, topics)


if __name__ == '__main__':
    rospy.init_node('config_error_test')
    rostest.rosrun('pbd_cloth', 'config_error', ConfigErrorTest, sys.argv)
