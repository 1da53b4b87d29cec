// Ground-aware mapping for MRPT -- gam-import: the parsing and conversion
// behind the importer (issue #16), kept apart from its command line so that
// tests/import/ can check each step. Every function throws ImportError with a
// one-line message naming the file (and line) at fault.
//
// Frames (MRPT 2.5): the rawlog gets CObservation3DRangeScan frames with
// range_is_depth = true (the depth is the z of the camera's optical frame:
// x right, y down, z forward), cameraParams = the pinhole intrinsics and
// sensorPose = MRPT's sensor frame (x forward, y left, z up) on the robot.
// The two camera frames are related by p_opt = R p_mrpt with
// R = [[0,-1,0],[0,0,-1],[1,0,0]] (opticalInSensorFrame()).
#pragma once

#include <mrpt/img/CImage.h>
#include <mrpt/math/CMatrixDynamic.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace gam::import
{
struct ImportError : std::runtime_error
{
	using std::runtime_error::runtime_error;
};

/** Pinhole intrinsics of a depth image (no distortion). */
struct Intrinsics
{
	int width = 0, height = 0;
	double fx = 0, fy = 0, cx = 0, cy = 0;
};

/** Throws unless the intrinsics are usable: positive size, fx and fy > 0 and
 * finite, 0 <= cx < width, 0 <= cy < height. `where` starts the message. */
void checkIntrinsics(const Intrinsics& k, const std::string& where);

/** What a camera .ini (or the command line) gives (see doc/tools/gam-import.md):
 * [camera] width height fx fy cx cy depth_scale sensor_pose label. */
struct CameraConfig
{
	std::optional<Intrinsics> intrinsics;  ///< all six keys, or none
	std::optional<double> depthScale;      ///< PNG value per metre
	std::optional<mrpt::poses::CPose3D> sensorPose;
	std::optional<std::string> label;
};

/** Reads a camera .ini: `key = value` lines, an optional `[camera]` section
 * header, comments after '#' or ';'. Unknown keys and bad numbers are errors. */
CameraConfig readCameraIni(const std::string& path);

/** "x y z yaw pitch roll" (metres, degrees; MRPT's CPose3D order). */
mrpt::poses::CPose3D parseSensorPose(const std::string& text, const std::string& where);

/** "width height fx fy cx cy". */
Intrinsics parseIntrinsics(const std::string& text, const std::string& where);

// ------------------------------------------------------------------ poses

/** The pose of the optical frame in MRPT's sensor frame: rotation R^T,
 * i.e. CPose3D(0,0,0, yaw -90 deg, pitch 0, roll -90 deg). */
mrpt::poses::CPose3D opticalInSensorFrame();

/** TUM pose: translation and unit quaternion (qx qy qz qw, normalized here). */
mrpt::poses::CPose3D poseFromTum(double tx, double ty, double tz, double qx, double qy, double qz, double qw);

/** The robot's pose in the world from the camera's optical pose in the world
 * (TUM groundtruth.txt) and the camera's sensorPose on the robot:
 * world<-robot = world<-optical (+) inverse(robot<-sensor (+) sensor<-optical). */
mrpt::poses::CPose3D robotFromCamera(const mrpt::poses::CPose3D& worldOptical, const mrpt::poses::CPose3D& sensorPose);

/** x, y and yaw of a 3D pose (what the mapper's 2D odometry carries). */
mrpt::poses::CPose2D to2D(const mrpt::poses::CPose3D& p);

struct TimedPose
{
	double t = 0;
	mrpt::poses::CPose3D pose;
};

/** TUM groundtruth.txt: "timestamp tx ty tz qx qy qz qw" per line, '#'
 * comments. Timestamps must increase strictly. */
std::vector<TimedPose> readGroundTruth(const std::string& path);

/** The pose at time t: linear in translation, slerp in rotation between the two
 * samples around t, if both are at most maxGap seconds from t; else nullopt. */
std::optional<mrpt::poses::CPose3D> poseAt(const std::vector<TimedPose>& gt, double t, double maxGap);

// ------------------------------------------------------------ frame lists

struct ListEntry
{
	double t = 0;
	std::string file;  ///< as written in the list (relative to the list's folder)
	int line = 0;
};

/** A TUM list: "timestamp filename" (depth.txt) or an associations file,
 * "t1 file1 t2 file2" (associate.py, either order): the depth pair is the one
 * whose file name contains "depth" (an error if both or neither do). '#'
 * comments. The depth timestamps must increase strictly. */
std::vector<ListEntry> readFrameList(const std::string& path);

/** The files of a folder ending in `ext` (lower case, e.g. ".png"), in natural
 * order (digit runs compared as numbers). */
std::vector<std::string> listFolder(const std::string& dir, const std::string& ext);

// -------------------------------------------------------------- the frames

/** One depth image ready to become a CObservation3DRangeScan. */
struct DepthFrame
{
	mrpt::math::CMatrix_u16 range;  ///< rows = height; 0 = no data
	float units = 0.001f;           ///< metres per range unit
	Intrinsics k;
	std::optional<mrpt::img::CImage> rgb;  ///< registered colour, if any
};

/** Loads a 16-bit single-channel PNG (TUM depth: value = depth * depthScale).
 * The range image keeps the stored values and units = 1/depthScale, so no
 * precision is lost. Errors: missing file, not a PNG, 8-bit or colour, size
 * different from k. */
DepthFrame loadDepthPng(const std::string& path, const Intrinsics& k, double depthScale);

/** An organized PCD cloud (x y z in metres, the camera's optical frame). */
struct PcdCloud
{
	int width = 0, height = 0;
	std::string dataKind;        ///< ascii, binary, binary_compressed
	std::vector<float> x, y, z;  ///< row-major, width*height
	std::vector<uint32_t> rgb;   ///< packed 0x00RRGGBB, empty without rgb/rgba
};

/** liblzf's decompressor (the format of PCD binary_compressed). Throws if the
 * data is corrupt or does not decompress to exactly outSize bytes. */
std::vector<uint8_t> lzfDecompress(const uint8_t* in, size_t inSize, size_t outSize);

/** Reads a PCD file (v0.7 / v0.6 header; DATA ascii, binary or
 * binary_compressed). It must have x, y, z (F 4 or 8) and be organized
 * (HEIGHT > 1). */
PcdCloud readPcd(const std::string& path);

struct IntrinsicsFit
{
	Intrinsics k;
	size_t points = 0;  ///< valid pixels used
	double rms_px = 0;  ///< rms of the u and v residuals
	double max_px = 0;  ///< largest residual
};

/** fx, cx from least squares of u = fx x/z + cx, fy, cy from v = fy y/z + cy,
 * over the valid pixels (finite, z > 0). Throws if fewer than 3 distinct
 * columns or rows are valid. */
IntrinsicsFit fitIntrinsics(const PcdCloud& c);

/** depth = z, quantized to `units` (round to nearest; z <= 0, NaN or beyond
 * 65535 units: no data, counted in *dropped). The rgb becomes the colour. */
DepthFrame depthFromPcd(const PcdCloud& c, const Intrinsics& k, float units, size_t* dropped = nullptr);

/** The observation: range image, range_is_depth, cameraParams (and the
 * colour image with cameraParamsIntensity = cameraParams, registered). */
mrpt::obs::CObservation3DRangeScan::Ptr makeObservation(
	const DepthFrame& f, const mrpt::poses::CPose3D& sensorPose, const std::string& label, double timestamp,
	float maxRange);
}  // namespace gam::import
