// Ground-aware mapping for MRPT -- scene simulator: sensor models.
//
// Kinect One (Kinect for Windows v2, time of flight) depth model
// ---------------------------------------------------------------
// * Image 512x424, horizontal FOV 70.6 deg, vertical FOV 60 deg (Microsoft
//   spec sheet). Pinhole intrinsics from the FOV: fx = (W/2)/tan(hfov/2) =
//   361.6 px, fy = (H/2)/tan(vfov/2) = 367.2 px, cx = (W-1)/2, cy = (H-1)/2
//   (calibrated units report fx ~ fy ~ 365 px). No lens distortion.
// * Valid depth 0.5 .. 4.5 m (spec "0.5-4.5 m"); outside it the pixel is 0.
// * Pixel ray in the sensor frame (MRPT: +X forward, +Y left, +Z up):
//   (1, (cx-c)/fx, (cy-r)/fy); the stored value is the depth along +X, i.e.
//   the convention of mrpt::obs::CObservation3DRangeScan with range_is_depth.
// * Axial noise, Gaussian, sigma(z, theta) in metres with z the depth [m] and
//   theta the incidence angle [rad] between the ray and the surface normal:
//       sigma = s * 1e-3 * (1.5 - 0.5 z + 0.3 z^2 + 0.1 z^1.5 theta^2/(pi/2 - theta)^2)
//   This is the form and the coefficients (mm) of the Kinect v2 axial noise
//   model fitted by Fankhauser et al., "Kinect v2 for Mobile Robot Navigation:
//   Evaluation and Modeling", ICAR 2015 (coefficients quoted from memory of
//   that paper). s = KinectParams::noise_scale (1 = the paper). It gives
//   1.3 mm at 1 m / 0 deg, 4.3 mm at 4 m / 0 deg, 9 mm at 3 m / 70 deg.
// * Grazing dropouts: a pixel whose incidence angle exceeds grazing_start
//   (70 deg) is dropped (0) with a probability growing linearly to 1 at
//   grazing_end (85 deg); ToF returns vanish at grazing incidence.
// * Flying pixels ("mixed pixels" of ToF cameras): a pixel whose true depth
//   differs from one of its 4 neighbours by more than
//   max(flying_jump_abs, flying_jump_rel * depth) is, with probability
//   flying_prob, replaced by a depth between its own and that neighbour's
//   (uniform in the middle 70 % of the gap). Only depth edges produce them.
// * Spikes: with probability spike_prob per pixel the value is replaced by a
//   uniform random depth in [min_range, max_range] (multipath outliers).
// * All randomness comes from the std::mt19937 given to render(), so a frame
//   is deterministic for a seed. noise=false disables every effect above
//   (only the range limits remain): exact depths for tests.
//
// Leddar IS16 model
// -----------------
// * 16 segments over 45 deg horizontally, ~3 deg vertically (LeddarTech IS16
//   spec: 45 deg x 3 deg beam variant), max range 50 m.
// * Segment i is centred on MRPT's CObservation2DRangeScan::getScanAngle(i)
//   for aperture = hfov and rightToLeft = true, i.e. -hfov/2 + i*hfov/15, and
//   is hfov/16 wide. sub_h x sub_v sub-rays cover each segment; the segment
//   returns the nearest Euclidean hit distance among them (the IS16 reports
//   the first echo per segment), plus Gaussian noise sigma (default 2.5 cm:
//   the spec gives +-5 cm accuracy), quantised to 1 cm. No hit within
//   max_range: invalid.
#pragma once

#include <random>
#include <vector>

#include "gam/sim/Scene.h"

namespace gam::sim
{
struct KinectParams
{
	int width = 512, height = 424;
	double hfov_deg = 70.6, vfov_deg = 60.0;
	double min_range = 0.5, max_range = 4.5;
	bool noise = true;
	double noise_scale = 1.0;
	double grazing_start_deg = 70.0, grazing_end_deg = 85.0;
	double flying_prob = 0.5;
	double flying_jump_abs = 0.05, flying_jump_rel = 0.04;
	double spike_prob = 1e-4;

	double fx() const;
	double fy() const;
	double cx() const { return 0.5 * (width - 1); }
	double cy() const { return 0.5 * (height - 1); }
	/** The documented axial sigma [m] for depth z [m] and incidence theta [rad]. */
	double sigma(double z, double theta) const;
	/** Probability of a grazing dropout for incidence theta [rad]. */
	double dropoutProb(double theta) const;
};

/** Per-pixel flags of a simulated depth frame. */
enum PixelFlag : uint8_t
{
	PixValid = 1,
	PixDropout = 2,  ///< removed by the grazing-angle model
	PixFlying = 4,   ///< mixed depth at an edge
	PixSpike = 8,
	PixOutOfRange = 16,  ///< no surface in [min_range, max_range]
	PixEdge = 32         ///< lies on a true depth discontinuity
};

struct DepthFrame
{
	int width = 0, height = 0;
	std::vector<float> depth;       ///< simulated depth along +X [m], 0 = no return
	std::vector<float> true_depth;  ///< exact depth [m], +inf = no surface within 20 m
	std::vector<float> incidence;   ///< incidence angle [rad] of the true hit
	std::vector<int> object_id;     ///< id of the surface hit (0 floor / none)
	std::vector<uint8_t> flags;
	/** Geometric visible footprint (noise-free): world xy of every true hit
	 * within the valid range (5 mm inside the surface hit), plus the z=0
	 * crossing of rays that go into a pit (hitting its walls or bottom, or
	 * nothing) when that crossing is within the valid range. */
	std::vector<Eigen::Vector2d> footprint;
	size_t idx(int r, int c) const { return size_t(r) * size_t(width) + size_t(c); }
};

class KinectModel
{
   public:
	KinectParams p;
	explicit KinectModel(const KinectParams& params = {}) : p(params) {}
	/** Renders one frame. sensorInWorld = robot pose ⊕ sensor pose on the robot. */
	DepthFrame render(const Scene& scene, const Pose3& sensorInWorld, std::mt19937& rng) const;
	/** Unit-less ray (x = 1) of pixel (r, c) in the sensor frame. */
	Eigen::Vector3d pixelRay(int r, int c) const;
};

struct LeddarParams
{
	int segments = 16;
	double hfov_deg = 45.0, vfov_deg = 3.0;
	int sub_h = 5, sub_v = 3;
	double max_range = 50.0, min_range = 0.0;
	bool noise = true;
	double sigma = 0.025;
	double quantum = 0.01;
	/** Centre angle of segment i [rad] (MRPT getScanAngle convention). */
	double segmentAngle(int i) const;
};

struct LeddarScan
{
	std::vector<float> range;  ///< metres (Euclidean from the sensor)
	std::vector<bool> valid;
	std::vector<int> object_id;
};

class LeddarModel
{
   public:
	LeddarParams p;
	explicit LeddarModel(const LeddarParams& params = {}) : p(params) {}
	LeddarScan scan(const Scene& scene, const Pose3& sensorInWorld, std::mt19937& rng) const;
};

}  // namespace gam::sim
