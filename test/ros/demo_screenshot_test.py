#!/usr/bin/python3
# demo.launch seen through rviz (demo_screenshot.test): starts a virtual X server and rviz with
# rviz/demo.rviz, grabs the screen while scripted_gripper carries the corner over, and counts the
# pixels of the cloth's colour, so the test fails when the mesh does not reach the screen (no
# markers, wrong frame, unlit or inside-out triangles, ...). The picture is kept in the test
# results directory and, with the launch argument output:=<file.png>, also written there (that is
# how doc/demo.png is made).
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import sys
import time

import rospy
import rostest

# Only system message types here: in a fresh catkin workspace the run_tests environment is cached
# before the package's own Python messages exist, so `import pbd_cloth.msg` would fail there.
from visualization_msgs.msg import MarkerArray

from screenshot_helpers import ScreenshotCase, is_cloth


class DemoScreenshotTest(ScreenshotCase):
    def setUp(self):
        super().setUp()
        self.grasped_since = None  # wall time the gripper marker turned to "holding"
        rospy.Subscriber('/cloth_node/markers', MarkerArray, self.on_markers, queue_size=1)

    def on_markers(self, msg):
        for marker in msg.markers:
            if marker.ns == 'grippers' and marker.id == 0:
                # Green while holding, yellow while open (ros_conversions.cpp).
                holding = marker.color.g > marker.color.r
                if holding and self.grasped_since is None:
                    self.grasped_since = time.time()
                elif not holding:
                    self.grasped_since = None

    def test_rviz_shows_the_cloth(self):
        display = self.start_display()
        self.start_rviz(display, rospy.get_param('~rviz_config'), 'demo_screenshot_rviz')

        # rviz is up and draws the markers; give it a moment to render the first frames.
        self.wait_for_subscriber('/cloth_node/markers', '/demo_screenshot_rviz', 40.0)
        time.sleep(2.0)

        # Mid-fold if it comes within the test's patience: the flap in the air makes the picture.
        min_pixels = rospy.get_param('~min_cloth_pixels', 2000)
        wait_for_fold = time.time() + 15.0
        while time.time() < wait_for_fold:
            grasped_since = self.grasped_since
            if grasped_since is not None and time.time() > grasped_since + 1.8:
                break
            time.sleep(0.05)
        (best_count,), best_ppm = self.best_grab(display, (is_cloth,), (min_pixels,), 10.0)

        where = self.keep(best_ppm, 'demo_screenshot.png', rospy.get_param('~output', ''))
        print('demo_screenshot: %d cloth pixels, picture in %s' % (best_count, where))
        self.assertGreaterEqual(best_count, min_pixels,
                                'only %d pixels of the cloth colour on screen (see %s)'
                                % (best_count, where))


if __name__ == '__main__':
    rospy.init_node('demo_screenshot_test')
    rostest.rosrun('pbd_cloth', 'demo_screenshot', DemoScreenshotTest, sys.argv)
