// Ground-aware mapping for MRPT
// Inverse sensor model (paper §IV.C, eq. 4-6): turns the voxels of a frame's
// 2.5D map and the detected ground into occupancy evidence for 2D cells.
// Pure code: the result is a per-cell probability of being occupied in the
// frame grid, which the MRPT map then fuses in log-odds.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "gam/core/CameraNoise.h"
#include "gam/core/ElevationGrid.h"
#include "gam/core/Parameters.h"
#include "gam/core/RrtGroundDetector.h"

namespace gam
{
struct IsmParams
{
	/** `ground_aware` (default): the model below (each voxel's own cell, the
	 * noise-aware band, drops, ...). `paper`: eq. (3)-(6) of the paper as we
	 * read them (see computePaper()): a ray model with Table I values and
	 * none of this implementation's extensions. */
	MethodVariant model = MethodVariant::GroundAware;
	double d_pth = 0.03;   ///< plane distance threshold [m]: |d| <= d_pth is ground
	double K_g = 0.3;      ///< ground gain: a ground voxel says P(occ) = 0.5 - K_g * G(d)
	double sigma2 = 0.02;  ///< variance of G(d) = exp(-d^2 / (2 sigma2)) [m^2]
	double K_n = 0.0005;   ///< density gain [m^3 per point]
	double d_min = 3.0;    ///< density offset of the sigmoid
	double K_m = 0.8;      ///< obstacle gain: P(occ) = 0.5 + 0.5 * K_m * P_rho
	/** Depth noise of the sensor, sigma(r) = c0 + c2 * r^2 [m] (defaults: the
	 * Kinect v1 model of Nguyen et al. 2012; a Kinect One is better, so these
	 * are conservative for it). Seen from the sensor at height h, a floor point
	 * at range r moves vertically by sigma(r) * h / r, and the ground band
	 * widens to d_pth + noise_sigmas * that: far floor is not an obstacle. */
	double depth_noise_c0 = 0.0012;
	double depth_noise_c2 = 0.0019;
	double noise_sigmas = 3.0;  ///< 0 = the paper's fixed d_pth
	/** Measure the floor's vertical scatter in each frame instead: the median
	 * sample std of the floor cells in 0.5 m range bins (bins with at least
	 * floor_noise_min_cells such cells; the model above fills the others). A
	 * Kinect One, a Kinect v1 at 5 m or a stereo camera then each get the band
	 * their own noise needs, with no per-sensor tuning. */
	bool measure_floor_noise = true;
	int floor_noise_min_cells = 10;
	double floor_noise_bin = 0.5;  ///< range bin of the measured floor noise [m]
	/** Judge a voxel by the mean of its N samples too: the band above is for
	 * one sample; the mean of N has sigma / sqrt(N), so its band is
	 * d_pth + noise_sigmas * sigma / sqrt(N). A 4 cm cable or a 5 cm pit
	 * bottom 4 m away lies inside the one-sample band (the floor scatter there
	 * is ~8 mm) but its 20 samples put the mean far outside the band of the
	 * mean (issue #17). Off = only z_min / z_max against the one-sample band. */
	bool mean_test = true;
	/** The mean test's fixed part d_pth (plane error, floor unevenness) taken
	 * from the floor itself too: per range bin, tau = the robust spread of the
	 * floor cells' means around the plane (1.4826 x their median |distance|),
	 * and the band of the mean of N samples is noise_sigmas * sqrt(tau^2 +
	 * sigma^2 / N). A flat floor seen by a good camera then lets a 3 cm
	 * depression 3.5 m away count, where d_pth alone would not (issue #13);
	 * never narrower than traversable_step;
	 * an uneven floor or a poor plane fit widens it by itself, up to the
	 * d_pth form (never wider). Off: d_pth. */
	bool measure_floor_offset = true;
	/** Count the deep samples too (issue #13 item 3). At the far wall of a hole
	 * one cell holds the floor behind the hole and the wall below it, which the
	 * camera sees from 0 down to w h / r: the mean of the cell stays near the
	 * floor and its deepest sample inside the one-sample band, yet dozens of
	 * its samples lie deeper than any floor sample would. A floor sample lies
	 * more than T below the plane with probability p0 = Phi(-T / s), where T
	 * = traversable_step for a camera whose samples are independent (time of
	 * flight: the binomial tail is then exact at any T, and the hazard's own
	 * size counts the most of a hole's wall) and T = max(traversable_step,
	 * noise_sigmas * s) for one whose samples share part of their error
	 * (active stereo, structured light: a whole group of samples moves
	 * together, so only the band's depth is safe) (s^2 = sigma^2 + tau^2: one sample's
	 * vertical noise and the measured spread of the cells' means, d_pth /
	 * noise_sigmas where unmeasured); a cell whose k such samples (of the N
	 * the 3-sigma rule kept) have P(Binomial(N, p0) >= k) < Phi(-noise_sigmas),
	 * the false-alarm rate of the band itself, is a drop, if k >=
	 * min_obstacle_points (a depth spike is not a hole). Off: the cell's
	 * z_min and mean only. */
	bool deep_sample_test = true;
	/** The deep-sample test's count above the plane, for a camera whose
	 * samples are independent (time of flight; issue #27's cable). Far away a
	 * low object's cell holds its front face, seen as rows 1 cm apart from 0
	 * up to its height, and a few samples of its top: its mean stays inside
	 * the mean test's band and its top sample inside the one-sample band, yet
	 * several of its samples lie higher than any floor sample would. A cell
	 * is an obstacle when (1) k of its N samples lie more than T =
	 * traversable_step above the plane with P(Binomial(N, Phi(-T / s)) >= k) <
	 * Phi(-noise_sigmas) and k >= min_obstacle_points (the deep-sample test's
	 * count, s as there), and (2) its samples spread more than one surface's
	 * do: N var / sigma^2 (sigma: one sample's vertical noise, the band's) is
	 * above the chi-square quantile of N - 1 degrees of freedom at
	 * Phi(-noise_sigmas) (Wilson-Hilferty). (2) keeps a ramp's cells, which
	 * lie on one surface above the floor where no patch applies, to the mean
	 * test: the count alone took a held-out ramp below 95 % free (2026-11-27).
	 * Off: the deep-sample test counts below the plane only. */
	bool raised_sample_test = true;
	/** A surface's samples moved along their rays by the range noise
	 * (issue #27). A depth sample's error lies along its ray: a wall at range
	 * r whose samples scatter by sigma(r) puts some of them into the floor
	 * cells in front of it, up to noise_sigmas * sigma(r) away (an
	 * active-stereo or structured-light camera: 10-15 cm at 4-5 m), and the
	 * face of a step down puts some into the floor beyond its edge. An
	 * obstacle (drop) cell gives no evidence when, along its ray from the
	 * sensor (toward the sensor, for a drop) and within noise_sigmas * sigma
	 * of its range plus half a cell (sigma from the camera's noise model, both
	 * parts; horizontally sigma rho / r), a cell of the same class, with
	 * nothing but unseen cells between them, reaches as high (deep), less the
	 * vertical share of that move (or a cell beyond the range the map judges,
	 * max_range or the range of trust, reaches as high: seen, judged nowhere;
	 * one that does not ends the walk), and explains its samples beyond the band:
	 * they are no more than that cell's noise puts there (n_w * moved / stay,
	 * plus noise_sigmas Poisson deviations; moved and stay from the normal
	 * distribution of the move, cell centres d apart) and nearer that count
	 * than n_w, what a surface of its own as dense as that cell would give,
	 * each in its Poisson deviations: |n - lambda| / sqrt(lambda) < (n_w -
	 * n) / sqrt(n_w). A low object's top spread over a few cells, as dense in
	 * each, keeps them all. Only cells whose centres
	 * are at least a cell apart are compared: a camera whose reach stays
	 * under half a cell changes nothing (3 sigma < 8.3 mm: the Kinect One
	 * nearer than 5.7 m, the Femto nearer than 3.9 m). Off: every such cell
	 * counts. */
	bool range_smear = true;
	/** Bumps and dips smaller than this are floor for the robot: its wheels
	 * cross them (the simulator's ground truth uses the same 2 cm). The band
	 * of the mean never gets narrower. [m] */
	double traversable_step = 0.02;
	/** Obstacle voxels with fewer samples give no evidence. What blocks the
	 * robot faces the camera: a 4 cm tall face 4.5 m away fills a d_r = 5 cm
	 * cell with ~16 samples of a 512x424 Kinect One (11 mm between pixels
	 * there). A surface seen at grazing incidence does not: a cell of floor
	 * 4.5 m away from 0.8 m up (80 deg) gets ~4 rays, fewer after dropouts,
	 * and so does the far side of a ramp (84 deg), whose one to three samples
	 * per cell sit a few cm off the landing's plane or above the floor's. A
	 * lone depth spike or flying pixel gives one sample, a pair of them two.
	 * So 3 (it was 2 for both kinds: floor false obstacles in door_opening
	 * 0.62 -> 0.35 %, see doc/benchmark.md). A drop takes this count too:
	 * seen from afar, the far side of a ramp is such a drop (a drop below the
	 * ground plane took 2 until 2026-11-27; the steps and holes it was for
	 * are marked as far with 3, doc/rules.md I12), and a drop that counts
	 * casts its drop ray (a ray took its own count, drop_ray_min_points, also
	 * 3, until 2026-11-29, doc/rules.md I16). A voxel judged by its top
	 * (bottom) sample while others lie in the band needs this many samples
	 * beyond the band (given the frame's samples): a spike among floor
	 * samples is no obstacle. */
	int min_obstacle_points = 3;
	/** Points more than this above the robot's floor (robot frame) do not
	 * block (ceiling, door frames, beams above the robot): the pipeline does
	 * not project them (GroundAwarePipeline's projection filter). The ISM
	 * itself takes the 2.5D map it is given (it dropped voxels this far above
	 * the ground plane too until 2026-11-29, which changed no map after the
	 * projection's crop, doc/rules.md I10). [m] */
	double robot_height = 1.8;
	/** Below-ground voxels also mark the cells between the point where their
	 * ray crossed the ground plane and the voxel: no floor was there. A drop
	 * voxel casts its ray when it counts (min_obstacle_points samples, below
	 * the band for a voxel judged by its bottom sample): one stray return (a
	 * depth spike, a reflection metres below the floor) must not paint a line
	 * of obstacles across the floor. */
	bool drop_rays = true;
	/** Use the tree's extra ground patches (ramps) near their nodes. */
	bool local_planes = true;
	/** How far from its nodes a ground patch applies. [m] */
	double plane_support_radius = 0.4;

	/** The .ini keys (paper Table I names), ranges and meanings (Parameters.h). */
	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(
			ParamInfo{
				"ism_model", 0, 1, "inverse sensor model: ground_aware | paper (eq. 4-6 as printed)",
				kMethodVariantNames},
			p.model);
		visit(ParamInfo{"d_pth", 1e-6, 10, "plane distance threshold [m]"}, p.d_pth);
		visit(ParamInfo{"K_g", 0, 0.499, "ground gain"}, p.K_g);
		visit(ParamInfo{"sigma2", 1e-9, 100, "variance of the ground Gaussian [m^2]"}, p.sigma2);
		visit(ParamInfo{"K_n", 1e-12, 1e6, "density gain [m^3/point]"}, p.K_n);
		visit(ParamInfo{"d_min", -1e6, 1e6, "density sigmoid offset"}, p.d_min);
		visit(ParamInfo{"K_m", 0, 0.999, "obstacle gain"}, p.K_m);
		visit(ParamInfo{"depth_noise_c0", 0, 1, "sensor depth noise sigma = c0 + c2 r^2: c0 [m]"}, p.depth_noise_c0);
		visit(ParamInfo{"depth_noise_c2", 0, 1, "c2 [1/m]"}, p.depth_noise_c2);
		visit(
			ParamInfo{"noise_sigmas", 0, 10, "ground band = d_pth + noise_sigmas * vertical noise; 0 = fixed d_pth"},
			p.noise_sigmas);
		visit(
			ParamInfo{"mean_test", 0, 1, "also judge a voxel by its mean against the band of the mean (sigma/sqrt(N))"},
			p.mean_test);
		visit(
			ParamInfo{
				"measure_floor_offset", 0, 1,
				"mean test: the plane error term from the floor cells' measured spread instead of d_pth"},
			p.measure_floor_offset);
		visit(
			ParamInfo{
				"deep_sample_test", 0, 1,
				"a cell with more samples far below the plane than floor noise explains is a drop"},
			p.deep_sample_test);
		visit(
			ParamInfo{
				"raised_sample_test", 0, 1,
				"time of flight: a cell with more samples above traversable_step than floor noise explains, spread "
				"over more than one surface, is an obstacle"},
			p.raised_sample_test);
		visit(
			ParamInfo{
				"range_smear", 0, 1,
				"an obstacle (drop) cell whose samples beyond the band are what the range noise of a cell of the "
				"same class behind (before) it along its ray, or of one as high beyond the judged range, moves there "
				"gives no evidence"},
			p.range_smear);
		visit(
			ParamInfo{"traversable_step", 0, 1, "bumps and dips smaller than this are floor for the robot [m]"},
			p.traversable_step);
		visit(
			ParamInfo{
				"min_obstacle_points", 1, 1000000,
				"obstacle/drop voxels with fewer samples are ignored (depth spikes)"},
			p.min_obstacle_points);
		visit(
			ParamInfo{
				"measure_floor_noise", 0, 1,
				"band from the floor's scatter measured in each frame (model where too little floor)"},
			p.measure_floor_noise);
		visit(
			ParamInfo{"floor_noise_min_cells", 1, 1000000, "floor cells a range bin needs to be measured"},
			p.floor_noise_min_cells);
		visit(ParamInfo{"floor_noise_bin", 0.05, 10, "range bin of the measured floor noise [m]"}, p.floor_noise_bin);
		visit(
			ParamInfo{"robot_height", 1e-3, 100, "points above this (robot frame) are not projected [m]"},
			p.robot_height);
		visit(ParamInfo{"drop_rays", 0, 1, "mark cells where rays went below the ground"}, p.drop_rays);
		visit(ParamInfo{"local_planes", 0, 1, "use ramp patches near their nodes"}, p.local_planes);
		visit(
			ParamInfo{"plane_support_radius", 0, 100, "reach of a ramp patch around its nodes [m]"},
			p.plane_support_radius);
	}
	/** Throws std::invalid_argument naming the parameter out of range. */
	void validate() const;
};

/** The formulas, exposed for tests. */
namespace ism
{
/** Points per cubic metre of a voxel: N_z / (d_r^2 * max(span, d_r)). */
double voxelDensity(uint32_t count, double span, double resolution);
/** Eq. (4): P_rho = 1 / (1 + exp(-(K_n * rho - d_min))). */
double densityConfidence(double rho, const IsmParams& p);
/** Eq. (5): P(occ) of an obstacle voxel, in [0.5, 0.5 + 0.5*K_m]. */
double obstacleProbability(double densityConfidence, const IsmParams& p);
/** Eq. (6): P(occ) of a ground voxel at plane distance d. */
double groundProbability(double d, const IsmParams& p);

/** P(X >= k) for X ~ Binomial(n, p): the chance that floor noise alone puts
 * k of a cell's n samples beyond the deep-sample threshold. */
double binomialTail(uint32_t n, double p, uint32_t k);
/** P(Z < -x) for a standard normal Z. */
inline double normalTail(double x) { return 0.5 * std::erfc(x / std::sqrt(2.0)); }
/** Whether x lies above the chi-square quantile of `dof` degrees of freedom
 * whose upper tail is P(Z > z) for a standard normal Z, by the
 * Wilson-Hilferty cube root: chi2 / dof ~ N(1 - 2 / (9 dof), 2 / (9 dof))^3
 * (at z = 3 at most 2 % above the quantile from 2 degrees of freedom on, 1 %
 * from 5). */
inline bool chiSquareAbove(double x, uint32_t dof, double z)
{
	if (dof == 0) return false;
	const double v = 2.0 / (9.0 * double(dof)), q = 1.0 - v + z * std::sqrt(v);
	return q > 0 && x > double(dof) * q * q * q;
}
/** The k-th smallest of v[0..n) (0-based, k < n; v is reordered), the value
 * std::nth_element puts at v[k]. A quickselect whose partition has no branch
 * per element: introselect branches on each comparison, which no predictor
 * learns on a bin's unordered noise values (measureFloorNoise; its medians took
 * 0.06-0.09 ms of a Kinect One demo frame with nth_element). No NaN in v. */
float kthSmallest(float* v, size_t n, size_t k);
/** Combines two pieces of evidence for one cell within a frame: occupied
 * evidence wins (the largest one), otherwise the strongest free one. */
inline float combine(float a, float b)
{
	if (a > 0.5f || b > 0.5f) return a > b ? a : b;
	return a < b ? a : b;
}
/** The strongest evidence a cell can get in one frame: P(occ) in
 * [kEvidenceFloor, 1 - kEvidenceFloor]. The grid clamps every update to it,
 * so evidence beyond it would change nothing. */
constexpr float kEvidenceFloor = 0.001f;
}  // namespace ism

/** The paper's model (ism_model = paper), written as printed:
 *  eq. (4) P_rho = K_m / (1 + exp(-K_n (N_z - d_min) / V_voxel)), with
 *          V_voxel = d_r^2 * max(z_max - z_min, d_r) (a one-sample voxel
 *          would have V = 0: we take it one cell tall);
 *  eq. (5) for a cell c on the voxel's ray with |c| <= |c_v| (2D distances
 *          from the sensor): obstacle voxel max(P_rho, 0.5) *
 *          exp(-(|c| - |c_v|)^2 / (2 sigma^2)); ground voxel
 *          K_g + (0.5 - K_g) / (1 + exp(-(|c| - |c_v|)));
 *  eq. (6) for |c| in ]|c_v|, |c_v|^max]: no evidence (0.5) -- see
 *          doc/paper-vs-implementation.md for this reading. */
namespace paper
{
// Inline: the sweep calls them per sample (an exported function is called
// through the library's PLT).
inline double voxelVolume(double span, double resolution)
{
	return resolution * resolution * std::max(span, resolution);
}
inline double densityConfidence(uint32_t count, double span, const IsmParams& p, double resolution)
{
	return p.K_m / (1.0 + std::exp(-p.K_n * (double(count) - p.d_min) / voxelVolume(span, resolution)));
}
inline double obstacleRay(double cDist, double cvDist, double pRho, const IsmParams& p)
{
	if (cDist > cvDist) return 0.5;  // eq. (6): behind the voxel, no evidence
	const double d = cDist - cvDist;
	return std::max(pRho, 0.5) * std::exp(-d * d / (2.0 * p.sigma2));
}
inline double groundRay(double cDist, double cvDist, const IsmParams& p)
{
	if (cDist > cvDist) return 0.5;
	return p.K_g + (0.5 - p.K_g) / (1.0 + std::exp(-(cDist - cvDist)));
}

/** The rays of the paper model, discretized: angular bins around the sensor,
 * fine enough that neighbouring rays are half a cell apart at the maximum
 * range, each sampled every d_r from the sensor at r_k = (k + 1/2) d_r. A
 * voxel's ray is the ray of its bin (within d_r / 4 of its true line) and
 * reaches the samples with r_k <= |c_v|; the cells of a ray are the cells
 * holding its samples. All voxels of a bin share its samples, which lets
 * computePaper() sweep each bin once from far to near. */
struct RayFan
{
	RayFan(double resolution, double maxRange)
		: res(resolution),
		  bins(std::max(8, int(std::ceil(4.0 * M_PI * maxRange / resolution)))),
		  dtheta(2.0 * M_PI / bins)
	{
	}
	double res;
	int bins;
	double dtheta;
	/** The bin of the direction (dx, dy) from the sensor: the nearest
	 * multiple of dtheta to its angle std::atan2(dy, dx), halves rounded away
	 * from zero (std::lround), modulo bins. Once per voxel, so without library
	 * calls where it can: the angle from atanReduced() (within 1e-10 rad of
	 * atan2's), and atan2 itself only where that could round to another bin
	 * (within 1e-9 rad of a bin's edge). */
	int binOf(double dx, double dy) const
	{
		const double ax = std::abs(dx), ay = std::abs(dy);
		const bool steep = ay > ax;
		const double lo = steep ? ax : ay, hi = steep ? ay : ax;
		double a = -1;  // |angle| / dtheta
		if (hi > 0 && hi < 1e300)
		{
			double t = atanReduced(lo / hi);  // the angle in [0, pi/4]
			if (steep) t = 0.5 * M_PI - t;
			if (dx < 0) t = M_PI - t;
			a = t / dtheta;
			if (std::abs(a - double(int(a)) - 0.5) <= 1e-9 / dtheta) a = -1;
		}
		if (a < 0) a = std::abs(std::atan2(dy, dx)) / dtheta;  // and atan2(0, -0) = pi
		if (!(a <= double(bins))) return 0;                    // a NaN
		// lround(a), and the sign of atan2's angle: std::signbit(dy) (a dy of
		// -0 with dx < 0 is -pi, the same bin as pi).
		int b = int(a);
		b += (a - double(b)) >= 0.5;
		if (std::signbit(dy)) b = -b;
		return ((b % bins) + bins) % bins;
	}
	/** atan(z) for z in [0, 1] within 1e-10: z brought to |u| <= tan(pi/16)
	 * around 0, pi/8 or pi/4 (atan z = c + atan((z - tan c) / (1 + z tan c))),
	 * then the series of atan u to u^11 (the next term, u^13 / 13, is below
	 * 6e-11). */
	static double atanReduced(double z)
	{
		constexpr double kTan1 = 0.19891236737965800;  // tan(pi/16)
		constexpr double kTan3 = 0.66817863791929890;  // tan(3 pi/16)
		constexpr double kTanPi8 = 0.41421356237309503;
		double c = 0, u = z;
		if (z >= kTan3)
		{
			c = 0.25 * M_PI;
			u = (z - 1.0) / (z + 1.0);
		}
		else if (z > kTan1)
		{
			c = 0.125 * M_PI;
			u = (z - kTanPi8) / (1.0 + z * kTanPi8);
		}
		const double u2 = u * u;
		const double series =
			1.0 + u2 * (-1.0 / 3 + u2 * (1.0 / 5 + u2 * (-1.0 / 7 + u2 * (1.0 / 9 + u2 * (-1.0 / 11)))));
		return c + u * series;
	}
	double angle(int bin) const { return bin * dtheta; }
	double radius(int k) const { return (k + 0.5) * res; }
	/** The last sample a voxel at 2D distance `dist` reaches (-1: none):
	 * floor(dist / res - 1/2 + 1e-9), the floor written out (t > -1 here):
	 * std::floor is a library call on a build for plain x86-64, once per voxel. */
	int lastSample(double dist) const
	{
		const double t = dist / res - 0.5 + 1e-9;
		return t < 0 ? -1 : int(t);
	}
};
}  // namespace paper

enum class VoxelClass : uint8_t
{
	None = 0,
	Ground,
	Obstacle,   ///< sticks out above the ground
	Drop,       ///< entirely below the ground: hole, outlet, downward step
	OutOfRange  ///< beyond max_range: ignored
};

struct IsmStats
{
	size_t ground = 0, obstacle = 0, drop = 0, out_of_range = 0;
	size_t sparse = 0;  ///< obstacle/drop voxels below min_obstacle_points: ignored
	size_t drop_ray_cells = 0;
	size_t drop_rays_unsupported = 0;  ///< drop rays not cast: an obstacle stood between the sensor and the crossing
	size_t deep_drops = 0;             ///< drops found by the deep-sample count alone
	size_t raised_obstacles = 0;       ///< obstacles found by the raised-sample count alone
	size_t smeared = 0;    ///< obstacle / drop cells whose samples beyond the band are another cell's (range_smear)
	bool applied = false;  ///< false when there was no ground plane
};

/** Where ramp or landing patches (planes[k], k >= 1) applied in an
 * InverseSensorModel::compute(), per block of frame cells: a view of the
 * model's own table (InverseSensorModel::patchSupport()). Empty: nowhere. */
struct PatchSupport
{
	const uint8_t* blocks = nullptr;
	size_t count = 0;     ///< blocks in the table
	int block_cells = 1;  ///< a block is block_cells x block_cells frame cells
	int blocks_x = 0;     ///< blocks per row of the table
	int nx = 0;           ///< frame grid width [cells]

	bool applies(uint32_t cell) const
	{
		if (!count || nx <= 0 || block_cells <= 0) return false;
		const int cx = int(cell % uint32_t(nx)), cy = int(cell / uint32_t(nx));
		const size_t block = size_t(cy / block_cells) * size_t(blocks_x) + size_t(cx / block_cells);
		return block < count && blocks[block] != 0;
	}
};

class InverseSensorModel
{
   public:
	/** Throws std::invalid_argument for parameters out of range. */
	explicit InverseSensorModel(const IsmParams& p = {}) { setParams(p); }
	/** The camera that took the frame (focal length fx [px]): with a
	 * correlated part in its noise (a stereo camera), the deep-sample test
	 * also judges a cell from its own level. Default: none (independent
	 * samples, a time-of-flight camera). */
	void setCameraNoise(const CameraNoise& noise, double fx)
	{
		m_camera = noise;
		m_fx = fx;
	}
	/** Where the frame's samples end: beyond `limit` [m] the camera (or the
	 * projection's max_range) returned nothing. Measured along `forward`,
	 * the camera's optical axis in the map frame as a unit vector (a depth
	 * image, cut on its depth), or as the range from the sensor when
	 * `forward` is zero (a range image or a point cloud). A surface just beyond the limit still
	 * returns the samples its range noise brings nearer, and only those:
	 * range_smear takes them for that surface's. Default: no limit. */
	void setCameraRangeLimit(const Eigen::Vector3d& forward, double limit)
	{
		m_rangeAxis = forward;
		m_rangeLimit = limit;
	}
	/** Validates (throws std::invalid_argument), then keeps `p`: compute()
	 * runs with parameters checked once, not on every frame. */
	void setParams(const IsmParams& p)
	{
		p.validate();
		m_params = p;
	}
	const IsmParams& params() const { return m_params; }

	/** Computes the evidence of one frame. `samples` are the heights the frame
	 * was built from, binned on its grid (for deep_sample_test and the tail
	 * counts; without them the test is skipped).
	 * `sensor` is the sensor position in
	 * the grid frame; voxels farther than `maxRange` from it (2D) are ignored.
	 * With no ground plane (det.ok() false) nothing is produced: a frame
	 * without ground never invents obstacles. */
	void compute(
		const ElevationGrid& frame, const GroundDetection& det, const Eigen::Vector3d& sensor, double maxRange,
		IsmStats& stats, const BinnedPoints* samples = nullptr);

	/** P(occupied) per frame cell; 0.5 where there is no evidence. */
	const std::vector<float>& evidence() const { return m_evidence; }
	/** Cells with evidence != 0.5 (indices into the frame grid). */
	const std::vector<uint32_t>& evidenceCells() const { return m_evidenceCells; }
	/** Whether a ramp or landing patch (planes[k], k >= 1) applies at frame
	 * cell `cell` of a grid `nx` cells wide in the last compute() (within
	 * plane_support_radius of its nodes, local_planes). */
	bool patchApplies(uint32_t cell, int nx) const { return patchSupport(nx).applies(cell); }
	/** The same for every cell, as a view (valid until the next compute()). */
	PatchSupport patchSupport(int nx) const { return {m_support.data(), m_support.size(), m_blockCells, m_bnx, nx}; }
	/** Class of each observed frame cell (None elsewhere). */
	const std::vector<VoxelClass>& classes() const { return m_class; }

	/** Classification of one voxel against one plane (exposed for tests).
	 * `band` is the one-sample ground band (groundBand()): a voxel whose top or
	 * bottom leaves it is an obstacle or a drop; with mean_test, so is one
	 * whose mean leaves d_pth + (band - d_pth) / sqrt(N). */
	VoxelClass classify(
		const ElevationCell& c, double x, double y, const Plane& pl, double band, double& dMean,
		double floorOffset = -1) const;
	/** The floor cells' measured spread around the plane at the range of
	 * (x, y, z) from `sensor` (measure_floor_offset), or -1 where unmeasured. */
	double floorOffset(const Eigen::Vector3d& sensor, double x, double y, double z) const;
	/** Half-width of the ground band for a voxel at (x, y, z) seen from `sensor`
	 * (h: sensor height over the plane): d_pth + noise_sigmas * the floor's
	 * vertical noise at that range, measured in the last compute() or modelled. */
	double groundBand(const Eigen::Vector3d& sensor, double sensorHeight, double x, double y, double z) const;

   private:
	/** Distance of (x, y, z) from the sensor: the range the floor-noise and
	 * floor-offset bins are indexed by. */
	static double rangeFrom(const Eigen::Vector3d& sensor, double x, double y, double z);
	/** Combines p into the cell's evidence; true when that made it leave
	 * 0.5 (ism::combine never brings it back): the cell is to be listed.
	 * Evidence of exactly 0.5 (K_g = 0 or K_m = 0) is no evidence: listing
	 * it put neutral cells, and duplicates, into evidenceCells(). */
	bool combineEvidence(uint32_t cell, float p)
	{
		float& e = m_evidence[cell];
		const bool wasNeutral = e == 0.5f;
		e = ism::combine(e, p);
		return wasNeutral && e != 0.5f;
	}
	/** combineEvidence(), listing the cell. Inline: every voxel calls it. */
	void put(uint32_t cell, float p)
	{
		if (combineEvidence(cell, p)) m_evidenceCells.push_back(cell);
	}
	void computePaper(
		const ElevationGrid& frame, const GroundDetection& det, const Eigen::Vector3d& sensor, IsmStats& stats);
	// Paper model workspace: in-range voxels sorted by (bin, distance
	// descending) with two counting sorts, and a bin's obstacle voxels whose
	// ray evidence has not yet fallen to kEvidenceFloor.
	struct PaperVoxel
	{
		uint32_t cell;
		int bin, last;  ///< ray bin; last sample reached (RayFan::lastSample)
		float dist;     ///< |c_v| [m]
		float peak;     ///< max(P_rho, 0.5); 0 for a ground voxel
	};
	std::vector<PaperVoxel> m_paperVoxels, m_paperSorted, m_paperActive;
	std::vector<uint32_t> m_paperCount;
	std::vector<double> m_paperExpNegR;     ///< e^-r_k per sample of the fan
	std::vector<uint32_t> m_paperNewCells;  ///< the sweep's newly listed cells
	const Plane& choosePlane(const GroundDetection& det, const ElevationCell& c, double x, double y, int block) const;
	/** P(occ) of an obstacle or drop voxel: eq. (4)-(5) of its density. */
	float obstacleEvidence(const ElevationCell& c, double resolution) const;
	CameraNoise m_camera;  ///< of the frame (setCameraNoise)
	double m_fx = 0;
	Eigen::Vector3d m_rangeAxis = Eigen::Vector3d::Zero();          ///< setCameraRangeLimit
	double m_rangeLimit = std::numeric_limits<double>::infinity();  ///< setCameraRangeLimit [m]
	/** Samples an obstacle or a drop voxel needs (min_obstacle_points). */
	uint32_t minPoints() const { return uint32_t(std::max(1, m_params.min_obstacle_points)); }
	void buildSupport(const GridGeometry& g, const GroundDetection& det);
	/** deep_sample_test: counts each candidate cell's kept samples below its
	 * threshold, then turns the cells that pass into drops. */
	/** Whether the nearest cell this frame observed between the sensor and a
	 * drop ray's crossing with the ground (ex, ey) is an obstacle tall enough
	 * to have stopped that ray (hs: the sensor's height over `pl`). */
	bool rayBlocked(
		const ElevationGrid& frame, const Plane& pl, const Eigen::Vector3d& sensor, double hs, double ex,
		double ey) const;
	/** Counts each candidate cell's kept samples beyond its threshold, then
	 * decides it: deep_sample_test (a floor cell becomes a drop), or an
	 * obstacle / drop judged by its extreme sample (min_obstacle_points of
	 * them beyond the band give evidence, and a drop's cast its ray);
	 * the cells that pass are held for range_smear when it applies. The
	 * counts stay until clearTailCandidates(). */
	void countTailSamples(const ElevationGrid& frame, const BinnedPoints& samples, IsmStats& stats);
	/** range_smear: whether the `beyond` samples above (below, `drop`) the
	 * band of the obstacle (drop) cell `cell` can be those of a cell of the
	 * same class farther along its ray (nearer, for a drop), within
	 * noise_sigmas of the camera's range noise, or (an obstacle) those of a
	 * surface beyond the frame's range limit (setCameraRangeLimit). Reads the
	 * frame's classes and the tail candidates' counts, so it runs after
	 * countTailSamples. */
	bool smeared(
		const ElevationGrid& frame, uint32_t cell, uint32_t beyond, bool drop, const Eigen::Vector3d& sensor) const;
	/** An obstacle or drop cell about to give evidence: its samples beyond
	 * the band, what it is, whether it casts a drop ray, whether the
	 * deep- (raised-) sample test made it a drop (an obstacle); range_smear's
	 * verdict. */
	struct Held
	{
		uint32_t cell;
		uint32_t beyond;
		bool drop, deep;
		bool smeared = false;
	};
	/** Gives the evidence now, or holds the cell for range_smear. */
	void hold(const Held& h, bool smear, const ElevationGrid& frame, IsmStats& stats);
	/** Puts an obstacle or drop cell's evidence (and, with drop_rays, a drop's ray). */
	void give(const Held& h, const ElevationGrid& frame, IsmStats& stats);
	/** Whether range_smear applies (on, a noise model, a focal length). */
	bool smearTest() const { return m_params.range_smear && m_params.noise_sigmas > 0 && m_fx > 0; }
	/** Resets the tail candidates' scratch tables (after range_smear). */
	void clearTailCandidates();
	void measureFloorNoise(const ElevationGrid& frame, const GroundDetection& det, const Eigen::Vector3d& sensor);

	std::vector<float> m_floorNoise;   ///< per bin: measured std [m], < 0 = not measured
	std::vector<float> m_floorOffset;  ///< per bin: spread of the floor cells' means [m], < 0 = not measured
	std::vector<float> m_offsetValue, m_offsetSorted;
	// Floor samples of all bins in one buffer (bounded by the cell count, so
	// never reallocated per frame): (bin, std) pairs, then grouped by bin.
	std::vector<uint32_t> m_noiseBin;
	std::vector<float> m_noiseValue, m_noiseSorted;
	std::vector<uint32_t> m_noiseBinStart;

	IsmParams m_params;
	double m_maxRange = 5.0;  ///< of the current compute() [m]
	std::vector<float> m_evidence;
	std::vector<uint32_t> m_evidenceCells;
	std::vector<VoxelClass> m_class;
	std::vector<uint32_t> m_classCells;
	std::vector<uint32_t> m_dropVoxels;
	std::vector<int32_t> m_rayCells;  ///< pass 2: the cell of each step of one drop ray
	// Cells decided by counting samples: per cell a low threshold height
	// (samples below count; -inf elsewhere) or a high one (+inf elsewhere),
	// the count, and p0 of the deep-sample test.
	enum class TailKind : uint8_t
	{
		Deep,    ///< deep_sample_test on a ground cell
		Raised,  ///< raised_sample_test on a ground cell
		Above,   ///< obstacle by its top sample
		Below    ///< drop by its bottom sample
	};
	struct TailCandidate
	{
		uint32_t cell;
		TailKind kind;
		float p0;
	};
	std::vector<TailCandidate> m_tailCandidates;
	std::vector<Held> m_held;  ///< obstacle and drop cells waiting for range_smear
	std::vector<float> m_tailLo, m_tailHi;
	std::vector<uint32_t> m_tailCount;
	std::vector<uint8_t> m_tailCell;      ///< 1 for the tail candidates' cells (during countTailSamples)
	std::vector<uint32_t> m_tailSamples;  ///< the samples in those cells (during countTailSamples)
	// Local-plane support raster: bit k set = plane k applies in that block.
	std::vector<uint8_t> m_support;
	int m_blockCells = 4, m_bnx = 0, m_bny = 0;
};

}  // namespace gam
