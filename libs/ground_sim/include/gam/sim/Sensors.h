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
#include <string>
#include <vector>

#include "gam/sim/Scene.h"

namespace gam::sim
{
/** The depth cameras the simulator models (see the presets in
 * cameraPreset() and doc/simulator.md for the makers' figures). */
enum class CameraModel
{
	KinectOne,  ///< time of flight, 512x424 (the default)
	D435,       ///< Intel RealSense D435, active stereo, 848x480
	D455,       ///< Intel RealSense D455, active stereo, 848x480
	Femto,      ///< Orbbec Femto Bolt / Azure Kinect, time of flight, 640x576 narrow mode
	Astra       ///< Orbbec Astra, structured light, 640x480
};

/** Parameters of one simulated depth camera. The defaults are the Kinect One;
 * cameraPreset() gives the other models. */
struct KinectParams
{
	CameraModel model = CameraModel::KinectOne;
	int width = 512, height = 424;
	double hfov_deg = 70.6, vfov_deg = 60.0;
	double min_range = 0.5, max_range = 4.5;
	bool noise = true;
	double noise_scale = 1.0;
	double grazing_start_deg = 70.0, grazing_end_deg = 85.0;
	double flying_prob = 0.5;
	double flying_jump_abs = 0.05, flying_jump_rel = 0.04;
	double spike_prob = 1e-4;

	// --- depth from disparity (active stereo, structured light): baseline > 0 ---
	/** Stereo baseline (projector-camera for structured light) [m]; 0 = time of flight. */
	double baseline = 0;
	double disp_sigma_px = 0;       ///< per-pixel disparity noise, sigma [px]
	double disp_corr_sigma_px = 0;  ///< spatially correlated disparity noise, rms [px]
	int disp_corr_px = 16;          ///< its correlation length (lattice spacing) [px]
	double disp_step_px = 0;        ///< disparity quantisation step [px] (0 = none)
	int fatten_px = 0;              ///< edges fattened toward the background by up to this [px]
	double fatten_prob = 0.7;       ///< probability that a background pixel that close takes the foreground's depth
	// --- time of flight: multipath in concave corners ---
	/** Extra range [m] of a floor pixel at the foot of a wall (and of a wall pixel
	 * at floor level); decays as exp(-s / multipath_decay) with the distance s to the corner. */
	double multipath_m = 0, multipath_decay = 0.3;

	bool fromDisparity() const { return baseline > 0; }

	double fx() const;
	double fy() const;
	double cx() const { return 0.5 * (width - 1); }
	double cy() const { return 0.5 * (height - 1); }
	/** The documented axial sigma [m] for depth z [m] and incidence theta [rad]:
	 * time of flight, the Kinect v2 model above (times noise_scale); from
	 * disparity, z^2 * sigma_d / (fx * baseline) with sigma_d the rms of the
	 * per-pixel and correlated disparity noise (no incidence term; quantisation
	 * not included). */
	double sigma(double z, double theta) const;
	/** Disparity [px] of depth z [m] (fx * baseline / z); 0 for time of flight. */
	double disparity(double z) const { return fromDisparity() ? fx() * baseline / z : 0.0; }
	/** Probability of a grazing dropout for incidence theta [rad]. */
	double dropoutProb(double theta) const;
};

/** The preset of a camera model (its resolution, field of view, range and noise). */
KinectParams cameraPreset(CameraModel model);
/** "kinect_one", "d435", "d455", "femto", "astra". */
const char* cameraModelName(CameraModel model);
/** The model of a name cameraModelName() gives; false for an unknown name. */
bool parseCameraModel(const std::string& name, CameraModel& model);
/** The names, comma separated (for error messages). */
std::string cameraModelNames();
/** The sensorLabel of a camera whose scene statement names none: "KINECT" for
 * the Kinect One (as before camera models existed), else the model's name in
 * capitals ("D435", "D455", "FEMTO", "ASTRA"), so that the map's
 * `camera_model = auto` reads the frames as the camera that took them. A D455
 * frame has a D435's size and field of view: only its label tells them apart. */
std::string defaultCameraLabel(CameraModel model);

/** Per-pixel flags of a simulated depth frame. */
enum PixelFlag : uint8_t
{
	PixValid = 1,
	PixDropout = 2,  ///< removed by the grazing-angle model
	PixFlying = 4,   ///< mixed depth at an edge
	PixSpike = 8,
	PixOutOfRange = 16,  ///< no surface in [min_range, max_range]
	PixEdge = 32,        ///< lies on a true depth discontinuity
	PixOccluded = 64,    ///< stereo: not seen by the second imager (or projector)
	PixFattened = 128    ///< stereo: took the depth of a nearer surface beside it
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

   private:
	/** Extra depth [m] per pixel from multipath in concave corners (ToF). */
	std::vector<float> multipathBias(
		const Pose3& sensorInWorld, const DepthFrame& f, const std::vector<float>& normalZ) const;
	/** Steps 3-4 for a camera with depth from disparity. */
	void renderDisparityNoise(const Scene& scene, DepthFrame& f, std::mt19937& rng) const;
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
	/** Horizontal angle of sub-ray a (0..sub_h-1) of segment i [rad]: sub_h
	 * directions from one edge of the segment's hfov/segments cone to the
	 * other, so that the nearest return found is the cone's, edges included
	 * (the echo of a wall seen obliquely comes from the cone's near edge). */
	double subRayAngle(int i, int a) const;
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
