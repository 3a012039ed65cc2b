#!/usr/bin/python3
# demo.launch seen through rviz (demo_screenshot.test): starts a virtual X server and rviz with
# rviz/demo.rviz, grabs the screen while scripted_gripper carries the corner over, and counts the
# pixels of the cloth's colour, so the test fails when the mesh does not reach the screen (no
# markers, wrong frame, unlit or inside-out triangles, ...). The picture is kept in the test
# results directory and, with the launch argument output:=<file.png>, also written there (that is
# how doc/demo.png is made).
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import rosgraph
import rospkg
import rospy
import rostest

# Only system message types here: in a fresh catkin workspace the run_tests environment is cached
# before the package's own Python messages exist, so `import pbd_cloth.msg` would fail there.
from visualization_msgs.msg import MarkerArray

# The mesh colour of ros_conversions.cpp, (0.85, 0.35, 0.2), lit: darker or lighter but still
# orange. Red clearly above green, green a good fraction of red (the red x axis of rviz's Axes
# display has none) and not below blue (the table, floor and grid are grey or blue-grey).
def is_cloth(r, g, b):
    return r >= 60 and r - g >= 40 and g >= 0.2 * r and g >= b


def read_ppm(data):
    """(width, height, pixels) of a binary PPM (P6, maxval 255) as convert writes it."""
    fields = []
    pos = 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b'#':
            pos = data.index(b'\n', pos)
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    if fields[0] != b'P6' or int(fields[3]) != 255:
        raise ValueError('not an 8-bit binary PPM')
    width, height = int(fields[1]), int(fields[2])
    return width, height, data[pos + 1:pos + 1 + 3 * width * height]


def count_cloth_pixels(ppm):
    _, _, pixels = read_ppm(ppm)
    count = 0
    for k in range(0, len(pixels), 3):
        if is_cloth(pixels[k], pixels[k + 1], pixels[k + 2]):
            count += 1
    return count


class DemoScreenshotTest(unittest.TestCase):
    def setUp(self):
        self.processes = []
        self.workdir = tempfile.mkdtemp(prefix='pbd_cloth_screenshot_')
        self.grasped_since = None  # wall time the gripper marker turned to "holding"
        rospy.Subscriber('/cloth_node/markers', MarkerArray, self.on_markers, queue_size=1)

    def tearDown(self):
        # Everything started here, by handle, newest first.
        for process in reversed(self.processes):
            if process.poll() is None:
                process.terminate()
                try:
                    process.wait(timeout=10.0)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
        shutil.rmtree(self.workdir, ignore_errors=True)

    def on_markers(self, msg):
        for marker in msg.markers:
            if marker.ns == 'grippers' and marker.id == 0:
                # Green while holding, yellow while open (ros_conversions.cpp).
                holding = marker.color.g > marker.color.r
                if holding and self.grasped_since is None:
                    self.grasped_since = time.time()
                elif not holding:
                    self.grasped_since = None

    def start(self, command, log_name, env=None):
        log = open(os.path.join(self.workdir, log_name), 'w')
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, env=env)
        self.processes.append(process)
        return process

    def start_display(self):
        for tool in ('Xvfb', 'xwd', '/usr/bin/convert', 'rviz'):
            self.assertTrue(shutil.which(tool), '%s is missing (scripts/setup_deps installs it)'
                            % tool)
        display = 99
        while (os.path.exists('/tmp/.X%d-lock' % display) or
               os.path.exists('/tmp/.X11-unix/X%d' % display)):
            display += 1
        self.start(['Xvfb', ':%d' % display, '-screen', '0', '1024x768x24', '-nolisten', 'tcp'],
                   'xvfb.log')
        deadline = time.time() + 10.0
        while not os.path.exists('/tmp/.X11-unix/X%d' % display):
            self.assertLess(time.time(), deadline, 'Xvfb did not start')
            time.sleep(0.1)
        return ':%d' % display

    def rviz_subscribed(self):
        _, subscribers, _ = rosgraph.Master('/demo_screenshot_test').getSystemState()
        for topic, nodes in subscribers:
            if topic == '/cloth_node/markers' and '/demo_screenshot_rviz' in nodes:
                return True
        return False

    def grab(self, display):
        xwd = subprocess.run(['xwd', '-root', '-silent', '-display', display],
                             stdout=subprocess.PIPE, check=True, timeout=20.0).stdout
        return subprocess.run(['/usr/bin/convert', 'xwd:-', 'ppm:-'], input=xwd,
                              stdout=subprocess.PIPE, check=True, timeout=20.0).stdout

    def save_png(self, ppm, path):
        directory = os.path.dirname(os.path.abspath(path))
        os.makedirs(directory, exist_ok=True)
        subprocess.run(['/usr/bin/convert', 'ppm:-', path], input=ppm, check=True, timeout=20.0)

    def test_rviz_shows_the_cloth(self):
        display = self.start_display()
        env = dict(os.environ, DISPLAY=display)
        self.start(['rviz', '-d', rospy.get_param('~rviz_config'), '__name:=demo_screenshot_rviz'],
                   'rviz.log', env)

        # rviz is up and draws the markers; give it a moment to render the first frames.
        deadline = time.time() + 40.0
        while not self.rviz_subscribed():
            self.assertLess(time.time(), deadline, 'rviz never subscribed to /cloth_node/markers')
            time.sleep(0.2)
        time.sleep(2.0)

        # Mid-fold if it comes within the test's patience: the flap in the air makes the picture.
        min_pixels = rospy.get_param('~min_cloth_pixels', 2000)
        wait_for_fold = time.time() + 15.0
        while time.time() < wait_for_fold:
            grasped_since = self.grasped_since
            if grasped_since is not None and time.time() > grasped_since + 1.8:
                break
            time.sleep(0.05)
        best_count, best_ppm = -1, None
        deadline = time.time() + 10.0
        while time.time() < deadline:
            ppm = self.grab(display)
            count = count_cloth_pixels(ppm)
            if count > best_count:
                best_count, best_ppm = count, ppm
            if count >= min_pixels:
                break
            time.sleep(1.0)

        results = rospkg.get_test_results_dir()
        kept = os.path.join(results, 'pbd_cloth', 'demo_screenshot.png')
        self.save_png(best_ppm, kept)
        output = rospy.get_param('~output', '')
        if output:
            self.save_png(best_ppm, output)
        print('demo_screenshot: %d cloth pixels, picture in %s' % (best_count, output or kept))
        self.assertGreaterEqual(best_count, min_pixels,
                                'only %d pixels of the cloth colour on screen (see %s)'
                                % (best_count, kept))


if __name__ == '__main__':
    rospy.init_node('demo_screenshot_test')
    rostest.rosrun('pbd_cloth', 'demo_screenshot', DemoScreenshotTest, sys.argv)
