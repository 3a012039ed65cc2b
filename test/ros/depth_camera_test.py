#!/usr/bin/python3
# Simulated depth cameras through ROS (depth_camera.test, scene depth_camera_scene.yaml):
# - each image has a CameraInfo and an organized PointCloud2 with the very same stamp and frame
#   (exact-time synchronizers pair them), stamped at the camera's ticks of simulated time;
# - layouts: 32FC1 image, K and P from the scene, cloud width x height with float32 x y z where
#   z is the image's depth and x, y its unprojection;
# - depth against the analytic scene: the cloth lying on the table, the bare table, the ball;
# - the camera following a tf frame sees what the posed one sees, the posed camera's frame is on
#   /tf_static, and the noisy camera differs from the clean one by the configured deviation.
#
# /usr/bin/python3 on purpose: a pyenv python3 earlier on PATH has no rospy.
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from sensor_msgs.msg import CameraInfo, Image, PointCloud2
from diagnostic_msgs.msg import DiagnosticArray
from tf2_msgs.msg import TFMessage

NODE = '/cloth_node'
CAMERAS = ['overhead', 'follower', 'noisy']
MIN_FRAMES = 6  # complete (image, info, cloud) triples per camera before checking


class DepthCameraTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        # camera -> kind -> {stamp (ns): message}
        self.got = {c: {'image': {}, 'info': {}, 'points': {}} for c in CAMERAS}
        self.static_frames = {}
        for camera in CAMERAS:
            base = '%s/%s/depth/' % (NODE, camera)
            rospy.Subscriber(base + 'image_raw', Image, self.keep, (camera, 'image'),
                             queue_size=50)
            rospy.Subscriber(base + 'camera_info', CameraInfo, self.keep, (camera, 'info'),
                             queue_size=50)
            rospy.Subscriber(base + 'points', PointCloud2, self.keep, (camera, 'points'),
                             queue_size=50)
        rospy.Subscriber('/tf_static', TFMessage, self.on_tf_static, queue_size=10)
        self.diagnostics = {}
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=10)
        self.scene = rospy.get_param(NODE)

    def keep(self, msg, key):
        camera, kind = key
        with self.lock:
            self.got[camera][kind][msg.header.stamp.to_nsec()] = msg

    def on_tf_static(self, msg):
        with self.lock:
            for t in msg.transforms:
                self.static_frames[t.child_frame_id] = t

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                for kv in status.values:
                    if kv.key.startswith('depth images'):
                        self.diagnostics[kv.key] = int(kv.value)

    def complete(self, camera, got=None):
        """Stamps with all three messages, in `got` (a snapshot) or in what arrived so far."""
        with self.lock:
            kinds = (got or self.got)[camera]
            return sorted(set(kinds['image']) & set(kinds['info']) & set(kinds['points']))

    def wait_for_frames(self):
        deadline = time.time() + 60.0
        while time.time() < deadline and not rospy.is_shutdown():
            if all(len(self.complete(c)) >= MIN_FRAMES for c in CAMERAS):
                # Let the messages of the newest stamps finish arriving.
                time.sleep(0.5)
                return
            time.sleep(0.1)
        self.fail('too few complete frames: %s' % {c: len(self.complete(c)) for c in CAMERAS})

    def config(self, name):
        return next(c for c in self.scene['cameras'] if c['name'] == name)

    @staticmethod
    def depth_of(image):
        return np.frombuffer(image.data, dtype='<f4').reshape(image.height, image.width)

    def pixel_of(self, camera, x, y, z):
        """The pixel that looks at the world point (x, y, z) from a camera looking straight down
        from its pose (optical z = world -z, x = world x, y = world -y)."""
        c = self.config(camera)
        height = 1.5  # the cameras' z in depth_camera_scene.yaml
        zc = height - z
        u = c['fx'] * x / zc + (c['width'] - 1) / 2.0
        v = c['fy'] * (-y) / zc + (c['height'] - 1) / 2.0
        return int(round(u)), int(round(v))

    def test_depth_cameras(self):
        self.wait_for_frames()
        with self.lock:
            got = {c: {k: dict(v) for k, v in kinds.items()} for c, kinds in self.got.items()}
        rate = self.config('overhead')['rate']

        for camera in CAMERAS:
            c = self.config(camera)
            frame = c['frame']
            stamps = self.complete(camera, got)
            images, infos, clouds = (got[camera][k] for k in ('image', 'info', 'points'))
            # Every image has its info and cloud with the same stamp: nothing is stamped apart.
            # Only images between the first and the last complete stamp count: this test's three
            # subscriptions connect one after another, so the first images may arrive before the
            # info or cloud subscription is connected, and the newest ones may still be on their
            # way.
            first, last = stamps[0], stamps[-1]
            for kind, messages in (('info', infos), ('points', clouds)):
                orphans = [s for s in images if first <= s <= last and s not in messages]
                self.assertEqual(orphans, [], '%s: images without a %s of the same stamp'
                                 % (camera, kind))
            for stamp in stamps:
                ticks = stamp * 1e-9 * rate
                self.assertAlmostEqual(ticks, round(ticks), delta=1e-6,
                                       msg='%s: stamp %d ns is not a tick of %g Hz'
                                       % (camera, stamp, rate))
                image, info, cloud = images[stamp], infos[stamp], clouds[stamp]
                for msg in (image, info, cloud):
                    self.assertEqual(msg.header.frame_id, frame)
                # Image layout.
                self.assertEqual(image.encoding, '32FC1')
                self.assertEqual((image.width, image.height), (c['width'], c['height']))
                self.assertEqual(image.step, 4 * c['width'])
                self.assertEqual(image.is_bigendian, 0)
                # CameraInfo: K and P from fx, fy and the image centre; no distortion.
                cx, cy = (c['width'] - 1) / 2.0, (c['height'] - 1) / 2.0
                self.assertEqual((info.width, info.height), (c['width'], c['height']))
                np.testing.assert_allclose(info.K, [c['fx'], 0, cx, 0, c['fy'], cy, 0, 0, 1])
                np.testing.assert_allclose(info.P, [c['fx'], 0, cx, 0, 0, c['fy'], cy, 0, 0, 0,
                                                    1, 0])
                self.assertTrue(all(d == 0.0 for d in info.D))
                # Cloud: organized, float32 x y z; z is the image's depth, x and y its
                # unprojection along the pixel's ray.
                self.assertEqual((cloud.width, cloud.height), (c['width'], c['height']))
                fields = {f.name: f for f in cloud.fields}
                for name, offset in (('x', 0), ('y', 4), ('z', 8)):
                    self.assertEqual(fields[name].offset, offset)
                    self.assertEqual(fields[name].datatype, 7)  # FLOAT32
                self.assertFalse(cloud.is_dense)
                self.assertEqual(cloud.row_step, cloud.point_step * cloud.width)
                points = np.frombuffer(cloud.data, dtype='<f4').reshape(
                    cloud.height, cloud.width, cloud.point_step // 4)
                depth = self.depth_of(image)
                np.testing.assert_array_equal(points[:, :, 2], depth)
                u = np.arange(c['width'])[None, :]
                v = np.arange(c['height'])[:, None]
                np.testing.assert_allclose(points[:, :, 0], (u - cx) * depth / c['fx'],
                                           atol=1e-6)
                np.testing.assert_allclose(points[:, :, 1], (v - cy) * depth / c['fy'],
                                           atol=1e-6)

        # Depth against the analytic scene, in the newest overhead image (the cloth has lain
        # still since the start): cloth at table top (0.5) + thickness (0.005), bare table, and
        # the ball's top (0.6 + 0.1), seen from 1.5 m.
        stamp = self.complete('overhead', got)[-1]
        depth = self.depth_of(got['overhead']['image'][stamp])
        for (x, y, z, what) in ((-0.075, 0.0, 0.505, 'cloth'), (-0.1, 0.1, 0.505, 'cloth'),
                                (0.2, 0.35, 0.5, 'table'), (0.35, 0.0, 0.7, 'ball top')):
            u, v = self.pixel_of('overhead', x, y, z)
            self.assertAlmostEqual(float(depth[v, u]), 1.5 - z, delta=1e-3,
                                   msg='%s at pixel (%d, %d)' % (what, u, v))

        # The tf-followed camera at the same pose sees the same image at the same stamps.
        shared = sorted(set(self.complete('overhead', got)) &
                        set(self.complete('follower', got)))
        self.assertGreater(len(shared), 2)
        for stamp in shared:
            a = self.depth_of(got['overhead']['image'][stamp])
            b = self.depth_of(got['follower']['image'][stamp])
            np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
            np.testing.assert_allclose(a[~np.isnan(a)], b[~np.isnan(b)], atol=1e-5)

        # The posed cameras' frames are broadcast as static transforms at their poses.
        deadline = time.time() + 5.0
        while time.time() < deadline and 'overhead_optical' not in self.static_frames:
            time.sleep(0.1)
        with self.lock:
            t = self.static_frames.get('overhead_optical')
        self.assertIsNotNone(t, 'overhead_optical not on /tf_static')
        self.assertEqual(t.header.frame_id, 'world')
        self.assertAlmostEqual(t.transform.translation.z, 1.5, places=6)
        self.assertAlmostEqual(abs(t.transform.rotation.x), 1.0, places=6)

        # The node's diagnostics count the images it published (three cameras).
        deadline = time.time() + 5.0
        while time.time() < deadline and \
                self.diagnostics.get('depth images published', 0) < 3 * MIN_FRAMES:
            time.sleep(0.1)
        with self.lock:
            diagnostics = dict(self.diagnostics)
        self.assertGreaterEqual(diagnostics.get('depth images published', 0), 3 * MIN_FRAMES,
                                str(diagnostics))
        # (Skipped images are reported too; the follower's static tf may start after the
        # node's first image, so their count is not asserted.)
        self.assertIn('depth images skipped (no tf for the camera)', diagnostics)

        # Noise: noisy minus overhead, same state, has the configured deviation (5 mm). 19200
        # pixels a frame: the sample deviation is within 2 % of it (relative error 0.5 %).
        shared = sorted(set(self.complete('overhead', got)) &
                        set(self.complete('noisy', got)))
        self.assertGreater(len(shared), 2)
        sigma = self.config('noisy')['noise']
        for stamp in shared[:3]:
            a = self.depth_of(got['overhead']['image'][stamp])
            b = self.depth_of(got['noisy']['image'][stamp])
            both = ~np.isnan(a) & ~np.isnan(b)
            self.assertGreater(both.sum(), 10000)
            self.assertAlmostEqual(float(np.std(b[both] - a[both])), sigma, delta=0.02 * sigma)
        first = self.depth_of(got['noisy']['image'][shared[0]]) - \
            self.depth_of(got['overhead']['image'][shared[0]])
        second = self.depth_of(got['noisy']['image'][shared[1]]) - \
            self.depth_of(got['overhead']['image'][shared[1]])
        self.assertFalse(np.allclose(np.nan_to_num(first), np.nan_to_num(second)),
                         'the noise must differ from image to image')


if __name__ == '__main__':
    rospy.init_node('depth_camera_test')
    rostest.rosrun('pbd_cloth', 'depth_camera', DepthCameraTest, sys.argv)
