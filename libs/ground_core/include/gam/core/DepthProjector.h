// Ground-aware mapping for MRPT
// Projects a depth (or range) image straight into 2.5D grid bins, without
// building an intermediate point cloud. Pure code: the caller passes the image
// memory, the pinhole intrinsics and the sensor pose in the grid frame.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "gam/core/ElevationGrid.h"
#include "gam/core/Parameters.h"

namespace gam
{
/** Pinhole intrinsics of the depth image (pixels). */
struct PinholeIntrinsics
{
	int width = 0, height = 0;
	double fx = 0, fy = 0, cx = 0, cy = 0;
	/** Lens distortion, plumb-bob / Brown-Conrady (as MRPT's TCamera::dist):
	 * radial k1, k2, k3 and tangential p1, p2. Pixels are undistorted when the
	 * ray table is built, so it costs nothing per frame. */
	double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
	bool operator==(const PinholeIntrinsics& o) const
	{
		return width == o.width && height == o.height && fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy &&
			   k1 == o.k1 && k2 == o.k2 && p1 == o.p1 && p2 == o.p2 && k3 == o.k3;
	}
	/** Throws std::invalid_argument naming the bad value. */
	void validate() const;
};

/** A read-only view of a 16-bit range image (row-major, `stride` elements per row). */
struct RangeImageView
{
	const uint16_t* data = nullptr;
	int rows = 0, cols = 0;
	size_t stride = 0;
	float units = 0.001f;  ///< metres per unit
	/** true: the value is the depth along the sensor +X axis (Kinect);
	 * false: the Euclidean range along the pixel ray. */
	bool is_depth = true;
	uint16_t at(int r, int c) const { return data[size_t(r) * stride + size_t(c)]; }
};

/** What the projector keeps. Heights are in the grid frame. */
struct ProjectionFilter
{
	float min_range = 0.0f;  ///< metres along the sensor +X (depth) or the ray (range)
	float max_range = 5.0f;
	float z_min = -std::numeric_limits<float>::infinity();
	float z_max = std::numeric_limits<float>::infinity();
	int decimation = 1;  ///< use every n-th row and column
	/** Drop flying pixels (the "mixed pixels" of ToF cameras at a depth edge,
	 * whose depth lies between the two surfaces): see DepthProjector. Not in
	 * the paper's method. */
	bool drop_flying_pixels = true;

	/** The .ini keys, shared by every map that projects depth frames. */
	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(ParamInfo{"z_min", -1e4, 1e4, "lowest z kept [m] (ground-aware grid: robot frame, floor = 0)"}, p.z_min);
		visit(ParamInfo{"z_max", -1e4, 1e4, "highest z kept [m]"}, p.z_max);
		visit(ParamInfo{"min_range", 0, 1e4, "closer sensor returns are dropped [m]"}, p.min_range);
		visit(ParamInfo{"max_range", 0.01, 1e4, "farther sensor returns are dropped [m]"}, p.max_range);
		visit(ParamInfo{"decimation", 1, 64, "use every n-th pixel row/column"}, p.decimation);
		visit(
			ParamInfo{"drop_flying_pixels", 0, 1, "drop the mixed pixels between the two sides of a depth edge"},
			p.drop_flying_pixels);
	}
	/** Ranges, z_min < z_max and min_range < max_range; throws std::invalid_argument. */
	void validate() const;
};

/** Rigid transform sensor -> grid frame (row-major rotation and translation).
 * The sensor frame is MRPT's: +X forward, +Y left, +Z up. */
struct RigidTransform
{
	Eigen::Matrix3f R = Eigen::Matrix3f::Identity();
	Eigen::Vector3f t = Eigen::Vector3f::Zero();
};

class DepthProjector
{
   public:
	/** Bins every valid pixel into `out` (appends). Pixels that are 0, beyond
	 * the range limits, outside the grid or the z band are skipped, and with
	 * f.drop_flying_pixels the flying pixels (isFlyingPixel, with a tolerance
	 * of one grid cell).
	 * Returns the number of pixels binned. Throws std::invalid_argument if the
	 * image and the intrinsics disagree. */
	size_t project(
		const RangeImageView& img, const PinholeIntrinsics& K, const RigidTransform& sensorToGrid,
		const ProjectionFilter& f, const ElevationGrid& grid, BinnedPoints& out);

	/** Use the AVX2 row loop where the CPU has it (default). Off: always the
	 * baseline SSE2 loop; both give bit-identical results (tested). */
	void setAllowAvx2(bool allow) { m_allowAvx2 = allow; }

	/** Number of pixels in the ray table (that of the last intrinsics used). */
	size_t rayTableSize() const { return m_rayY.size(); }
	/** Ray factors (y/x, z/x) of pixel (row, col): the sensor-frame point of
	 * depth D is (D, D*y/x, D*z/x). */
	Eigen::Vector2f rayFactor(int row, int col) const
	{
		const size_t i = size_t(row) * size_t(m_lutK.width) + size_t(col);
		return {m_rayY[i], m_rayZ[i]};
	}

	/** The ray factors of one row of the table (width entries each). */
	const float* rayYRow(int row) const { return m_rayY.data() + size_t(row) * size_t(m_lutK.width); }
	const float* rayZRow(int row) const { return m_rayZ.data() + size_t(row) * size_t(m_lutK.width); }

	/** The range of a row's ray factors (see rowRayBounds). */
	struct RayBounds
	{
		float y_min, y_max, z_min, z_max;
	};
	/** The smallest and largest ray factors of one row of the table: lets a
	 * caller tell a whole row's rays apart from a plane without reading them. */
	const RayBounds& rowRayBounds(int row) const { return m_rowRayBounds[size_t(row)]; }

	/** A flying pixel: along its row or its column (neighbours `step` pixels
	 * apart), its depth d lies strictly between its two neighbours a and b,
	 * more than `tol` from each, and it continues neither side's surface: on
	 * a plane the inverse depth is affine in the pixel coordinates, so the
	 * two pixels on each side predict it (1 / (2/a - 1/a2)); it is more than
	 * `tol` from both predictions. Both sides of an edge can mix, so two
	 * adjacent pixels within `tol` of each other are tested as one such pixel
	 * too. A mixed pixel at a depth edge is flying; a floor seen at a grazing
	 * angle (steep but affine in inverse depth), the wall of a hole
	 * (continuous with its neighbour on the wall, or farther than both) and a
	 * thin object (nearer than both neighbours) are not. Next to a no-return
	 * (a background beyond the range) a pixel is flying when its other
	 * neighbour is nearer by more than `tol` and 5 % of its depth, it
	 * continues neither that side nor a return just past the gap, and no
	 * surface goes on from it: none of its 8 neighbours is within `tol` with
	 * the next pixel the same way within `tol` of that one (the floor past a
	 * step's edge goes on along its row). Depths and `tol` in the image's
	 * units; 0 = no return (a side with a 0 predicts nothing). project()
	 * drops these pixels but for the second pixel of a pair that the side
	 * beyond its partner continues linearly (|2 p1 - p2 - d| <= tol / 2): its
	 * fast first pass keeps that one (5-13 pixels a frame on simulated Kinect
	 * One and Femto frames, of the pixels this function flags). */
	static bool isFlyingPixel(const RangeImageView& img, int row, int col, int step, float tol);

	/** Whether the AVX2 row loop can run here (CPU and build). */
	static bool avx2Available();

   private:
	void updateLut(const PinholeIntrinsics& K);
	/** The decimated ray table for step `dec` > 1 (after updateLut). */
	void updateDecimatedLut(int dec);
	PinholeIntrinsics m_lutK;
	// Ray table, one entry per pixel, as separate arrays so the row loop vectorizes.
	std::vector<float> m_rayY, m_rayZ;  // y/x and z/x
	std::vector<float> m_rayInvNorm;    // 1 / |(1, y/x, z/x)|, for range images
	std::vector<RayBounds> m_rowRayBounds;
	// With decimation n > 1: the ray table and the frame's pixels of every
	// n-th row and column (contiguous: the row loop and the flying-pixel
	// filter run on them as on a smaller camera's frame).
	int m_decStep = 0;
	std::vector<float> m_decRayY, m_decRayZ, m_decRayInvNorm;
	std::vector<uint16_t> m_decImage;
	// One row of results before compaction (cell or -1, z).
	std::vector<int32_t> m_rowCell;
	std::vector<float> m_rowZ;
	std::vector<uint8_t> m_rowKeep;  // 0: a flying pixel
	// The flying-pixel filter's candidates of one row: columns, their two
	// lines (14 x width floats) and the answers of the tests.
	std::vector<int32_t> m_flyCols;
	std::vector<float> m_flyLines;
	std::vector<uint8_t> m_flyAlong, m_flyAgainstNothing;
	std::vector<uint16_t> m_flyZeros;  // a row of 0 (beyond the image's edge)
	bool m_allowAvx2 = true;
};

}  // namespace gam
