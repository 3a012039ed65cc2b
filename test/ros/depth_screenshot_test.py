#!/usr/bin/python3
# demo.launch seen through rviz/depth.rviz (depth_screenshot.test): starts a virtual X server and
# rviz, waits until rviz subscribes to the head camera's cloud (the node renders only while
# someone listens) and a cloud has arrived, then grabs the screen and counts the cyan pixels of
# the cloud and the orange pixels of the cloth. The test fails when either is missing: no depth
# cloud (camera not rendering, wrong frame, stamps rviz cannot place in tf) or no cloth. The
# picture is kept in the test results directory and, with output:=<file.png>, also written there
# (that is how doc/depth.png is made).
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import sys
import time

import rospy
import rostest
from sensor_msgs.msg import PointCloud2

from screenshot_helpers import ScreenshotCase, is_cloth

CLOUD_TOPIC = '/cloth_node/head_camera/depth/points'


# The cloud's flat colour in rviz/depth.rviz, cyan (0, 255, 255), drawn unlit: high green and blue,
# little red. The grid and background are grey, rviz's own blue has green far below blue, the
# cloth is orange.
def is_cloud(r, g, b):
    return g >= 170 and b >= 170 and r <= 110


class DepthScreenshotTest(ScreenshotCase):
    def setUp(self):
        super().setUp()
        self.clouds = 0
        rospy.Subscriber(CLOUD_TOPIC, PointCloud2, self.on_cloud, queue_size=1)

    def on_cloud(self, _):
        self.clouds += 1

    def test_rviz_shows_the_depth_cloud(self):
        display = self.start_display()
        self.start_rviz(display, rospy.get_param('~rviz_config'), 'depth_screenshot_rviz')
        self.wait_for_subscriber(CLOUD_TOPIC, '/depth_screenshot_rviz', 40.0)
        deadline = time.time() + 20.0
        while self.clouds < 5:
            self.assertLess(time.time(), deadline, 'no depth cloud on %s' % CLOUD_TOPIC)
            time.sleep(0.1)
        time.sleep(2.0)  # rviz draws the newest clouds

        min_cloud = rospy.get_param('~min_cloud_pixels', 5000)
        min_cloth = rospy.get_param('~min_cloth_pixels', 500)
        (cloud, cloth), ppm = self.best_grab(display, (is_cloud, is_cloth), (min_cloud, min_cloth),
                                             6.0)

        where = self.keep(ppm, 'depth_screenshot.png', rospy.get_param('~output', ''))
        print('depth_screenshot: %d cloud pixels, %d cloth pixels, picture in %s'
              % (cloud, cloth, where))
        self.assertGreaterEqual(cloud, min_cloud, 'only %d pixels of the cloud colour on screen '
                                '(see %s)' % (cloud, where))
        self.assertGreaterEqual(cloth, min_cloth, 'only %d pixels of the cloth colour on screen '
                                '(see %s)' % (cloth, where))


if __name__ == '__main__':
    rospy.init_node('depth_screenshot_test')
    rostest.rosrun('pbd_cloth', 'depth_screenshot', DepthScreenshotTest, sys.argv)
