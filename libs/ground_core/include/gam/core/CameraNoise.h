// Ground-aware mapping for MRPT
// The depth noise of the camera that took a frame, and how far the map can
// trust it (issue #27). A camera's depth error decides what the map can tell
// apart: a floor sample at range r seen from height h moves vertically by
// sigma(r) h / r, so a 2 cm step that a time-of-flight camera shows plainly at
// 5 m is lost in an active-stereo camera's noise at 3 m. The presets are the
// noise the makers publish (cited in doc/cameras.md; the simulator's camera
// models use the same figures). Pure code: no I/O.
#pragma once

#include <string_view>

#include "gam/core/Parameters.h"

namespace gam
{
/** The camera models the map knows; `auto` picks one from the frame. */
enum class CameraModel : int
{
	Auto = 0,
	KinectOne = 1,
	D435 = 2,
	D455 = 3,
	Femto = 4,
	Astra = 5,
	Custom = 6
};
inline constexpr const char* kCameraModelNames[] = {"auto",  "kinect_one", "d435",   "d455",
													"femto", "astra",      "custom", nullptr};

/** Axial depth noise sigma(z) of one pixel, in two parts:
 *  - independent per pixel: tof_c0 + tof_c1 z + tof_c2 z^2 (time of flight)
 *    plus z^2 hypot(disp_sigma, disp_step / sqrt(12)) / (fx baseline) (depth
 *    from disparity: per-pixel matching noise and the sub-pixel steps);
 *  - correlated over a cell and its neighbours, which averaging the cell's
 *    samples does not remove: z^2 disp_corr_sigma / (fx baseline) (the
 *    stereo matching window, the projector's pattern).
 * Lengths in metres, disparities in pixels. */
struct CameraNoise
{
	double tof_c0 = 0, tof_c1 = 0, tof_c2 = 0;
	double baseline = 0;  ///< stereo / projector-camera baseline [m]; 0 = no disparity term
	double disp_sigma = 0, disp_corr_sigma = 0, disp_step = 0;

	/** The part of one sample's sigma [m] that averages out over a cell's samples. */
	double independent(double z, double fx) const;
	/** The part that does not. */
	double correlated(double z, double fx) const;
};

/** The preset of a model (Custom and Auto: all zero). */
CameraNoise cameraNoisePreset(CameraModel model);

/** The model a frame comes from, guessed from its sensor label (case-blind:
 * "d455"; "d435" or "realsense"; "femto" or "azure"; "astra", "xtion",
 * "primesense", "carmine", "openni", "kinect_v1", "kinect1" or "kinectv1"
 * (structured light); "kinect_one", "kinectone", "kinect2" or "kinect_v2"),
 * else from its image
 * size and horizontal field of view: 512x424 Kinect One; 640x576 or 320x288
 * Femto (narrow mode); 848x480, 1280x720, 640x360 and 424x240 at 80-95 deg
 * D435 (the noisier of the two D400 models the map knows); 640x480 or 320x240
 * at 55-64 deg Astra (structured light, as a Kinect v1: 57 deg, 62.7 deg
 * registered to its colour camera). Custom when nothing
 * matches: a frame of unknown noise (the mapper says so). */
CameraModel detectCameraModel(std::string_view label, int width, int height, double fx);

/** How far (horizontal distance from the sensor [m]) the map can tell a
 * hazard `hazard` high (or deep) from floor noise, for a camera `height`
 * above the floor with focal length fx [px] on cells `resolution` wide: the
 * farthest rho from which noiseSigmas x sigma of a cell's mean floor height
 * stays within `hazard`, where a cell at slant range r = hypot(rho, h) holds
 * N = resolution^2 fx^2 h / r^3 samples (one pixel covers r / fx across and
 * r^2 / (fx h) along the ray), one sample's vertical sigma is sigma(r) h / r,
 * and the mean's is sqrt(correlated^2 + independent^2 / N) (N >= 1).
 * Searched in 1 cm steps up to `maxRange`, which it returns when the camera
 * is good enough everywhere (and for height <= 0 or fx <= 0). */
double trustRange(
	const CameraNoise& noise, double fx, double height, double resolution, double noiseSigmas, double hazard,
	double maxRange);

/** The camera parameters of the ground-aware map (`_groundOpts` keys). */
struct CameraParams
{
	/** Whose noise the map assumes: a preset, `auto` (from the frame, see
	 * detectCameraModel()) or `custom` (the custom_* coefficients below). */
	CameraModel model = CameraModel::Auto;
	/** Voxels beyond the range of trust give no evidence (cells stay unknown,
	 * not occupied, where the camera cannot tell the smallest hazard from
	 * floor noise). The hazard is ism.traversable_step, at ism.noise_sigmas. */
	bool range_of_trust = true;
	CameraNoise custom;

	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(
			ParamInfo{
				"camera_model", 0, 6, "depth camera noise: auto | kinect_one | d435 | d455 | femto | astra | custom",
				kCameraModelNames},
			p.model);
		visit(
			ParamInfo{"range_of_trust", 0, 1, "no evidence where the camera cannot tell traversable_step from noise"},
			p.range_of_trust);
		visit(
			ParamInfo{"custom_noise_c0", 0, 1, "camera_model=custom: ToF sigma = c0 + c1 z + c2 z^2, c0 [m]"},
			p.custom.tof_c0);
		visit(ParamInfo{"custom_noise_c1", -1, 1, "c1 [-]"}, p.custom.tof_c1);
		visit(ParamInfo{"custom_noise_c2", 0, 1, "c2 [1/m]"}, p.custom.tof_c2);
		visit(
			ParamInfo{"custom_baseline", 0, 10, "stereo/projector baseline [m] (0: no disparity noise)"},
			p.custom.baseline);
		visit(ParamInfo{"custom_disp_sigma", 0, 100, "per-pixel disparity noise [px]"}, p.custom.disp_sigma);
		visit(ParamInfo{"custom_disp_corr_sigma", 0, 100, "correlated disparity noise [px]"}, p.custom.disp_corr_sigma);
		visit(ParamInfo{"custom_disp_step", 0, 10, "disparity quantisation step [px]"}, p.custom.disp_step);
	}
};

}  // namespace gam
