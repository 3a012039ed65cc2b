#!/usr/bin/python3
# robot_demo.launch seen through rviz (robot_screenshot.test): starts a virtual X server and rviz
# with rviz/robot.rviz, waits (in tf, as robot_state_publisher publishes it) until the arm's wrist
# has passed through the plane the cloth hangs in, within the cloth's width, then grabs the screen
# and counts the pixels of the arm's colour and of the cloth's. The test fails when either is
# missing: no RobotModel (robot_description, tf or the package:// meshes not found), or no cloth
# mesh. The picture is kept in the test results directory and, with the launch argument
# output:=<file.png>, also written there (that is how doc/robot.png is made).
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import sys
import time

import rospy
import rostest
import tf2_ros

from screenshot_helpers import ScreenshotCase, is_cloth


# The arm's material `teal` of urdf/demo_arm.urdf, (0.10, 0.62, 0.72), lit: little red, blue
# near green. rviz's own blue (the display names in the panel, about (40, 120, 197)) has blue far
# above green, the grid is grey, the axes pure red, green or blue, the cloth orange.
def is_robot(r, g, b):
    return g >= 40 and 2 * r <= g and 0.8 * g <= b <= 1.4 * g


class RobotScreenshotTest(ScreenshotCase):
    def setUp(self):
        super().setUp()
        self.tf_buffer = tf2_ros.Buffer()
        self.tf_listener = tf2_ros.TransformListener(self.tf_buffer)

    def arm_in_cloth(self):
        """The wrist 4 cm beyond the cloth's rest plane (y = 0 in config/robot_demo.yaml; the
        sweep takes it up to 6.6 cm and holds it at 4.7), between the cloth's side edges
        (|x| < 0.2875): the forearm is deep in the cloth, pushing it."""
        try:
            wrist = self.tf_buffer.lookup_transform('world', 'wrist', rospy.Time(0))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException,
                tf2_ros.ExtrapolationException):
            return False
        position = wrist.transform.translation
        return position.y > 0.04 and abs(position.x) < 0.27

    def test_rviz_shows_the_arm_in_the_cloth(self):
        display = self.start_display()
        self.start_rviz(display, rospy.get_param('~rviz_config'), 'robot_screenshot_rviz')

        # rviz is up and draws the markers; give it a moment to render the first frames.
        self.wait_for_subscriber('/cloth_node/markers', '/robot_screenshot_rviz', 40.0)
        time.sleep(2.0)

        # The sweep comes once per pass of the looping script (31 s).
        deadline = time.time() + 70.0
        while not self.arm_in_cloth():
            self.assertLess(time.time(), deadline, 'the wrist never reached the cloth in tf')
            time.sleep(0.05)

        min_robot = rospy.get_param('~min_robot_pixels', 1500)
        min_cloth = rospy.get_param('~min_cloth_pixels', 2000)
        # The wrist stays that deep for about 3 s.
        (robot, cloth), ppm = self.best_grab(display, (is_robot, is_cloth), (min_robot, min_cloth),
                                             3.0, interval=0.5)

        where = self.keep(ppm, 'robot_screenshot.png', rospy.get_param('~output', ''))
        print('robot_screenshot: %d arm pixels, %d cloth pixels, picture in %s'
              % (robot, cloth, where))
        self.assertGreaterEqual(robot, min_robot, 'only %d pixels of the arm colour on screen '
                                '(see %s)' % (robot, where))
        self.assertGreaterEqual(cloth, min_cloth, 'only %d pixels of the cloth colour on screen '
                                '(see %s)' % (cloth, where))


if __name__ == '__main__':
    rospy.init_node('robot_screenshot_test')
    rostest.rosrun('pbd_cloth', 'robot_screenshot', RobotScreenshotTest, sys.argv)
