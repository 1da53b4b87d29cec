#!/usr/bin/python3
# Ground-aware mapping for MRPT -- tests: writes a small ROS 1 bag (Debian's
# python3-rosbag and message packages, no ROS install) for the rosbag2rawlog
# recipe of doc/tools/gam-import.md.
#
# usage: make_test_bag.py OUT.bag [16UC1|32FC1] [IMAGE_FRAME_ID]
# 3 frames at t = 100.0, 100.1, 100.2 s; the robot drives along x (0, 0.1, 0.2 m):
#   /tf        odom -> base_link          (x = 0, 0.1, 0.2)
#   /tf_static base_link -> camera_link   (0.1, 0, 0.5), identity rotation (x forward, z up)
#              camera_link -> camera_depth_optical_frame  the ROS optical rotation
#              (z forward, x right, y down: q = (x -0.5, y 0.5, z -0.5, w 0.5))
#   /camera/depth/image_raw    16x12 depth, frame IMAGE_FRAME_ID (default camera_depth_optical_frame):
#              2.0 m everywhere except row 0 (1.0 m) and pixel (row 11, col 15) = 0 (no data)
#   /camera/depth/camera_info  fx = fy = 10, cx = 7.5, cy = 5.5
#   /odom      nav_msgs/Odometry odom -> base_link, the same poses
import struct
import sys

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image
from tf2_msgs.msg import TFMessage

out = sys.argv[1]
encoding = sys.argv[2] if len(sys.argv) > 2 else "16UC1"
frame = sys.argv[3] if len(sys.argv) > 3 else "camera_depth_optical_frame"
W, H = 16, 12


def tf(stamp, parent, child, t, q):
    m = TransformStamped()
    m.header.stamp = stamp
    m.header.frame_id = parent
    m.child_frame_id = child
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = t
    m.transform.rotation.x, m.transform.rotation.y, m.transform.rotation.z, m.transform.rotation.w = q
    return m


with rosbag.Bag(out, "w") as bag:
    t0 = rospy.Time(100, 0)
    static = TFMessage()
    static.transforms = [
        tf(t0, "base_link", "camera_link", (0.1, 0.0, 0.5), (0, 0, 0, 1)),
        tf(t0, "camera_link", "camera_depth_optical_frame", (0, 0, 0), (-0.5, 0.5, -0.5, 0.5)),
    ]
    bag.write("/tf_static", static, t0)
    for i in range(3):
        stamp = rospy.Time(100, i * 100000000)
        x = 0.1 * i
        msg = TFMessage()
        msg.transforms = [tf(stamp, "odom", "base_link", (x, 0, 0), (0, 0, 0, 1))]
        bag.write("/tf", msg, stamp)

        odo = Odometry()
        odo.header.stamp = stamp
        odo.header.frame_id = "odom"
        odo.child_frame_id = "base_link"
        odo.pose.pose.position.x = x
        odo.pose.pose.orientation.w = 1.0
        bag.write("/odom", odo, stamp)

        img = Image()
        img.header.stamp = stamp
        img.header.frame_id = frame
        img.height, img.width = H, W
        img.encoding = encoding
        img.is_bigendian = 0
        data = bytearray()
        for r in range(H):
            for c in range(W):
                d = 1.0 if r == 0 else 2.0
                if r == H - 1 and c == W - 1:
                    d = 0.0
                data += struct.pack("<H", int(d * 1000)) if encoding == "16UC1" else struct.pack("<f", d)
        img.step = len(data) // H
        img.data = bytes(data)
        bag.write("/camera/depth/image_raw", img, stamp)

        info = CameraInfo()
        info.header = img.header
        info.height, info.width = H, W
        info.distortion_model = "plumb_bob"
        info.D = [0.0] * 5
        info.K = [10.0, 0, 7.5, 0, 10.0, 5.5, 0, 0, 1]
        info.R = [1.0, 0, 0, 0, 1, 0, 0, 0, 1]
        info.P = [10.0, 0, 7.5, 0, 0, 10.0, 5.5, 0, 0, 0, 1, 0]
        bag.write("/camera/depth/camera_info", info, stamp)
print("wrote", out, encoding)
