# What the rviz screenshot tests share (demo_screenshot_test.py, robot_screenshot_test.py): a
# virtual X server and processes started by handle, the screen grabbed as a PPM, pixel counting
# by colour, and the picture saved as PNG.
#
# Imported from the test scripts' own directory (a script's directory is first on sys.path).
import os
import select
import shutil
import subprocess
import tempfile
import time
import unittest

import rosgraph
import rospkg


# The cloth mesh colour of ros_conversions.cpp, (0.85, 0.35, 0.2), lit: darker or lighter but
# still orange. Red clearly above green, green a good fraction of red (the red x axis of rviz's
# Axes display has none) and not below blue (the table, floor and grid are grey or blue-grey).
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


def count_pixels(ppm, *predicates):
    """How many pixels satisfy each predicate(r, g, b), in order."""
    _, _, pixels = read_ppm(ppm)
    counts = [0] * len(predicates)
    for k in range(0, len(pixels), 3):
        r, g, b = pixels[k], pixels[k + 1], pixels[k + 2]
        for i, predicate in enumerate(predicates):
            if predicate(r, g, b):
                counts[i] += 1
    return counts


class ScreenshotCase(unittest.TestCase):
    """A virtual display, rviz on it, and everything started here stopped by handle."""

    def setUp(self):
        self.processes = []
        self.workdir = tempfile.mkdtemp(prefix='pbd_cloth_screenshot_')

    def tearDown(self):
        self.report_processes()
        # Everything started here, by handle, newest first.
        for process, _ in reversed(self.processes):
            if process.poll() is None:
                process.terminate()
                try:
                    process.wait(timeout=10.0)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
        shutil.rmtree(self.workdir, ignore_errors=True)

    def start(self, command, log_name, env=None):
        log = open(os.path.join(self.workdir, log_name), 'w')
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, env=env)
        self.processes.append((process, log_name))
        return process

    def report_processes(self, lines=10):
        """Prints, for the test's output (kept in its result file, and shown by
        scripts/count_test_results when the test failed), whether each process started here still
        runs and the end of its log: an rviz or Xvfb that died or complained is the first thing to
        look at when a picture is wrong."""
        for process, log_name in self.processes:
            code = process.poll()
            print('screenshot: %s %s' % (log_name, 'running' if code is None
                                         else 'exited with status %d' % code))
            try:
                with open(os.path.join(self.workdir, log_name), errors='replace') as log:
                    tail = [line for line in log.read().splitlines() if line.strip()][-lines:]
            except OSError as error:
                tail = ['(unreadable: %s)' % error]
            for line in tail:
                print('screenshot:   ' + line[:300])

    def start_display(self):
        for tool in ('Xvfb', 'xwd', '/usr/bin/convert', 'rviz'):
            self.assertTrue(shutil.which(tool), '%s is missing (scripts/setup_deps installs it)'
                            % tool)
        # Xvfb picks a free display itself and writes its number to a pipe (-displayfd) once it
        # listens: two screenshot tests started side by side (scripts/run_tests runs rostests two
        # at a time), or another checkout's, cannot take the same one, as they could when this
        # looked for a free lock file and then started Xvfb on it.
        read_end, write_end = os.pipe()
        log = open(os.path.join(self.workdir, 'xvfb.log'), 'w')
        process = subprocess.Popen(['Xvfb', '-displayfd', str(write_end), '-screen', '0',
                                    '1024x768x24', '-nolisten', 'tcp'],
                                   stdout=log, stderr=subprocess.STDOUT, pass_fds=(write_end,))
        self.processes.append((process, 'xvfb.log'))
        os.close(write_end)
        number = b''
        deadline = time.time() + 10.0
        while not number.endswith(b'\n'):
            ready, _, _ = select.select([read_end], [], [], max(0.0, deadline - time.time()))
            self.assertTrue(ready, 'Xvfb did not start')
            chunk = os.read(read_end, 16)
            self.assertTrue(chunk, 'Xvfb did not start (it exited: %s)' % process.poll())
            number += chunk
        os.close(read_end)
        return ':%d' % int(number)

    def start_rviz(self, display, config, node_name):
        env = dict(os.environ, DISPLAY=display)
        self.start(['rviz', '-d', config, '__name:=%s' % node_name], 'rviz.log', env)

    def wait_for_subscriber(self, topic, node, timeout):
        """Until `node` subscribes to `topic` (rviz is up and has loaded its displays)."""
        master = rosgraph.Master('/screenshot_test')
        deadline = time.time() + timeout
        while True:
            _, subscribers, _ = master.getSystemState()
            if any(t == topic and node in nodes for t, nodes in subscribers):
                return
            self.assertLess(time.time(), deadline, '%s never subscribed to %s' % (node, topic))
            time.sleep(0.2)

    def grab(self, display):
        xwd = subprocess.run(['xwd', '-root', '-silent', '-display', display],
                             stdout=subprocess.PIPE, check=True, timeout=20.0).stdout
        return subprocess.run(['/usr/bin/convert', 'xwd:-', 'ppm:-'], input=xwd,
                              stdout=subprocess.PIPE, check=True, timeout=20.0).stdout

    def best_grab(self, display, predicates, minimums, seconds, interval=1.0, accept=None):
        """Grabs the screen every `interval` s for up to `seconds` and returns (counts, ppm) of the
        best picture: counts of the pixels each predicate accepts, the best being the one whose
        smallest count / minimum ratio is largest. Stops early at a picture whose counts all reach
        their minimums (and that `accept(counts)` accepts, when given)."""
        best_score, best = -1.0, None
        deadline = time.time() + seconds
        while True:
            ppm = self.grab(display)
            counts = count_pixels(ppm, *predicates)
            score = min(c / float(m) for c, m in zip(counts, minimums))
            good = score >= 1.0 and (accept is None or accept(counts))
            if good or score > best_score:
                best_score, best = (float('inf') if good else score), (counts, ppm)
            if good or time.time() + interval > deadline:
                return best
            time.sleep(interval)

    def save_png(self, ppm, path):
        directory = os.path.dirname(os.path.abspath(path))
        os.makedirs(directory, exist_ok=True)
        subprocess.run(['/usr/bin/convert', 'ppm:-', path], input=ppm, check=True, timeout=20.0)

    def keep(self, ppm, name, output):
        """Saves the picture in the test results directory and, when asked, at `output`;
        returns where it is to be found."""
        kept = os.path.join(rospkg.get_test_results_dir(), 'pbd_cloth', name)
        self.save_png(ppm, kept)
        if output:
            self.save_png(ppm, output)
        return output or kept
