// Ground-aware mapping for MRPT
// Missing floor (issue #13): where the ground plane says a depth pixel should
// have returned the floor within the sensor's range, and the camera returned
// nothing (0) or something far below it, the floor is not there as seen --
// a hole deeper than the range, a black or absorbing surface, a pit behind
// glass. Such cells form a third state next to free and occupied.
//
// Floor that merely drops out (a ToF camera at grazing incidence, a shiny
// patch) must not look like a hole, so a cell is judged against the dropout
// rate of the floor seen in the same frame at the same range (rays in cells
// that got samples): with a
// per-ray dropout rate q, independent dropouts leave all n rays of a cell
// empty with probability q^n. Real cameras drop out in blocks (a stereo or
// structured-light matching window fails as a whole), so the frame also
// measures how often a pixel next to an empty pixel is empty too, on floor it
// did see (p11; = q for independent dropouts): a row of n empty rays then has
// the chance q * max(q, p11)^(n-1). The cell is missing floor only when that
// chance is below `alpha`. Missing cells are kept per connected region, and
// only regions with floor seen in the frame next to them, along the rays,
// both nearer to the sensor and farther away: a gap inside the floor, not the place where the
// returns stop (a range cutoff) or start (the robot's own body). The shadow
// of a step down is a gap too: beyond it, a lower surface where the edge's
// shadow ends, or, when that lies beyond the range, nothing up to the end of
// the range; its cells are judged together (step_shadows).
// Pure code: no MRPT, no I/O; no heap allocation per frame once sized.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "gam/core/DepthProjector.h"
#include "gam/core/ElevationGrid.h"
#include "gam/core/InverseSensorModel.h"
#include "gam/core/Parameters.h"
#include "gam/core/PlaneFit.h"
#include "gam/core/SensorFrame.h"

namespace gam
{
struct MissingFloorParams
{
	bool enabled = true;
	/** A cell needs at least this many empty rays to be judged. */
	int min_rays = 3;
	/** Largest chance q^n that floor with the measured dropout rate q leaves a
	 * cell's n rays all empty, for the cell to count as missing floor. */
	double alpha = 1e-3;
	/** Range bins of the measured dropout rate [m] (depth along +X). */
	double range_bin = 0.5;
	/** Missing floor within this 2D distance of the sensor is folded into the
	 * occupancy grid as an obstacle (the robot must stop before it); beyond it
	 * it is only in the missing-floor layer. Default: it always blocks. [m] */
	double block_range = 1000.0;
	/** A return at least this much deeper than the floor point its ray should
	 * have met counts as "no floor" (a hole deeper than the range); nearer
	 * returns beyond the range are floor noise at the range limit. [m] */
	double beyond_margin = 0.10;
	/** The dropout statistics (q, p11) come from every n-th image row (106
	 * rows of a 424-row frame are plenty); the empty rays of every row are
	 * counted. A speed setting: 1 = every row. */
	int stats_row_step = 4;
	/** The shadow of a step down, judged as one region: cells with too few
	 * empty rays to count alone (their chance above alpha) are judged
	 * together with the connected ones, when beyond them lies a surface
	 * below the ground where the edge's shadow on it ends
	 * (missing::isStepShadow). Near the end of a camera's range, where the
	 * floor drops out often and the rows are sparse, no cell of a step's
	 * shadow holds enough rays alone; a region of them does. And a shadow
	 * whose lower surface lies beyond the range (or the grid) is closed by
	 * the range's end: its rays start at seen floor with nothing seen above
	 * them nearer and run through unseen cells to the end of the range
	 * inside the image, and its cells are rarer than any cluster of floor
	 * dropouts that large, judged against every ray at the same distance
	 * from the sensor (see compute()). */
	bool step_shadows = true;

	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(
			ParamInfo{"missing_floor", 0, 1, "mark floor that returned no depth where the ground predicts it"},
			p.enabled);
		visit(ParamInfo{"missing_floor_min_rays", 1, 65535, "empty rays a cell needs to be judged"}, p.min_rays);
		visit(
			ParamInfo{"missing_floor_alpha", 1e-300, 1, "max chance that dropping-out floor leaves a cell this empty"},
			p.alpha);
		visit(ParamInfo{"missing_floor_bin", 0.05, 10, "range bin of the measured dropout rate [m]"}, p.range_bin);
		visit(
			ParamInfo{
				"missing_floor_block_range", 0, 1e6,
				"missing floor within this distance of the sensor is an obstacle in the grid [m]"},
			p.block_range);
		visit(
			ParamInfo{"missing_floor_beyond_margin", 0, 100, "a return this far below the floor is no floor [m]"},
			p.beyond_margin);
		visit(
			ParamInfo{"missing_floor_stats_rows", 1, 1000, "the dropout statistics use every n-th image row"},
			p.stats_row_step);
		visit(
			ParamInfo{
				"missing_floor_step_shadows", 0, 1,
				"judge the shadow of a step down as one region (its cells have too few rays alone), also when it runs "
				"to the end of the range"},
			p.step_shadows);
	}
	/** Throws std::invalid_argument naming the parameter out of range. */
	void validate() const;
};

struct MissingFloorStats
{
	size_t rays = 0;        ///< pixels whose ray meets the ground within range
	size_t empty_rays = 0;  ///< of those, no return (or one far below the floor)
	size_t candidates = 0;  ///< cells with no sample, enough empty rays, unlikely as dropout
	size_t cells = 0;       ///< missing-floor cells (in regions bordering floor)
	size_t regions = 0;     ///< their connected regions
	size_t unbordered =
		0;  ///< candidate regions dropped: no seen floor before, or neither floor nor a step's lower surface beyond
	size_t pooled_regions = 0;  ///< regions kept on their weak candidates' evidence together
	size_t range_end_regions =
		0;  ///< components of unbordered regions kept as a step's shadow that runs to the end of the range (rule MF11)
	size_t blocking = 0;             ///< missing cells within block_range
	size_t under_patches = 0;        ///< cells of bordered regions left out: a ramp or landing patch applies there
	size_t dead_border_columns = 0;  ///< image columns at the left and right borders with no return in the frame
	bool applied = false;            ///< the stage ran on this frame
};

namespace missing
{
/** The chance that floor with per-ray dropout rate q leaves all n rays of a
 * cell empty, when a ray next to an empty one is empty with probability p11
 * (a Markov chain along the rays): q * max(q, p11)^(n-1); q^n for
 * independent dropouts (p11 = q). */
double emptyCellChance(double q, double p11, int n);

/** Depth from disparity (active stereo, structured light): a pixel returns
 * depth only if the second imager (or the projector), `baseline` to the
 * image's right, sees its point too. A point at column c and depth z appears
 * there at column c - fx baseline / z; left of column 0 (rounded as
 * std::lround) it is outside that view: the invalid band at the image's left
 * edge, fx baseline / z pixels wide. Such a pixel returns nothing whatever
 * lies there. */
bool outsideSecondImager(int c, double z, double fxBaseline);

/** The dead bands at an image's borders: how many columns from the left
 * border, and from the right one, hold no return (raw 0) in any row. A
 * depth image registered to a colour camera (a Kinect v1's or an OpenNI
 * camera's, as PCL and ROS publish them) has such bands where the depth
 * camera's view does not cover the colour camera's; empty pixels there say
 * nothing about the floor. A hole or a drop empties a whole column only
 * where nothing else stands within the range in that column either: the
 * column's upper rows look past the hole at what lies beyond. ({cols, 0}
 * for an image without a single return.) */
std::pair<int, int> deadBorderColumns(const RangeImageView& img);

/** Whether a gap in the floor is the shadow of a step down: seen floor ends
 * at the edge, `edge` from the sensor (2D), which is `height` above the
 * floor; the gap ends where a surface `drop` below the floor is seen, `far`
 * from the sensor. The ray over the edge descends height / edge per metre,
 * so it meets that surface drop * edge / height beyond the edge: the gap is
 * the step's shadow if far - edge is that long, within `slack` (sampling).
 * A longer gap could be a ramp down seen at too grazing an angle to return
 * anything; a shorter one is no edge's shadow. */
bool isStepShadow(double edge, double far, double drop, double height, double slack);
}  // namespace missing

class MissingFloorDetector
{
   public:
	explicit MissingFloorDetector(const MissingFloorParams& p = {}) { setParams(p); }
	/** Validates (throws std::invalid_argument), then keeps `p`. */
	void setParams(const MissingFloorParams& p)
	{
		p.validate();
		m_params = p;
	}
	const MissingFloorParams& params() const { return m_params; }
	/** The camera's stereo (or projector) baseline [m], second imager to the
	 * image's right; 0 (time of flight) = every pixel could have returned.
	 * With a baseline, empty pixels of depth images that the second imager
	 * cannot see are no evidence: those in its invalid band at the image's
	 * left edge (missing::outsideSecondImager) and those whose floor point a
	 * nearer surface of the same row hides from it (the band left of a near
	 * object: a point at column k and disparity d_k lands at lround(k - d_k)
	 * there, and one more than half a pixel of disparity nearer than the
	 * floor point hides it). */
	void setSecondImagerBaseline(double baseline) { m_baseline = baseline > 0 ? baseline : 0; }
	/** How far before maxRange the camera's depth noise may carry a floor
	 * return beyond it [m] (depth): empty rays there are no evidence that a
	 * step's shadow runs to the end of the range. */
	void setRangeEndMargin(double margin) { m_rangeEndMargin = margin > 0 ? margin : 0; }

	/** One depth frame (frame.has_image) after the 2.5D map, the ground and
	 * the ISM classes of that frame are known (`classes`: None exactly for
	 * the cells `grid` did not observe, as InverseSensorModel::classes()
	 * gives them). `projector` holds the ray
	 * table of frame.intrinsics (its project() ran on this frame);
	 * `decimation` is the projection's; `maxRange` the range within which the
	 * sensor returns floor (depth for depth images, range along the ray for
	 * range images) [m]. Missing floor is judged against the ground plane:
	 * where a ramp or landing patch applies (`patches`), that plane says
	 * neither where the rays meet the surface nor at which incidence (a
	 * ramp's far, down-going side returns nothing at grazing incidence), so
	 * no cell there is missing floor (stats.under_patches counts them). */
	void compute(
		const SensorFrame& frame, const DepthProjector& projector, int decimation, double maxRange, const Plane& ground,
		const ElevationGrid& grid, const std::vector<VoxelClass>& classes, MissingFloorStats& stats,
		const PatchSupport& patches = {});
	/** Forgets the last frame's cells. */
	void clear();

	/** Missing-floor cells of the last frame (frame-grid indices). */
	const std::vector<uint32_t>& cells() const { return m_cells; }
	/** Those within block_range of the sensor. */
	const std::vector<uint32_t>& blockingCells() const { return m_blocking; }
	bool isMissing(uint32_t cell) const { return cell < m_mark.size() && (m_mark[cell] & kMissing); }
	/** Missing and within block_range of the sensor (one of blockingCells()). */
	bool isBlocking(uint32_t cell) const { return cell < m_mark.size() && (m_mark[cell] & kBlocking); }
	/** Empty rays per frame cell in the last frame (0 where none). */
	uint16_t emptyRays(uint32_t cell) const { return cell < m_empty.size() ? m_empty[cell] : 0; }
	/** The dropout rate of seen floor measured in the last frame at depth
	 * `depth`: of the rays that met the ground in that range bin, in cells
	 * that have samples, the share that returned nothing (a hole's own rays do
	 * not inflate it); 1 where there was no such ray (no evidence). */
	double dropoutRate(double depth) const;
	/** How often the next pixel of a row is empty after an empty one, both
	 * meeting the ground in cells where floor was seen (-1: no such pair). */
	double neighbourDropoutRate() const { return m_p11; }

   private:
	static constexpr uint8_t kCandidate = 1, kMissing = 2, kVisited = 4, kBlocking = 8, kWeak = 16, kJudged = 32;
	MissingFloorParams m_params;
	std::vector<uint16_t> m_empty;   ///< per frame cell
	std::vector<uint8_t> m_mark;     ///< per frame cell
	std::vector<float> m_logChance;  ///< per weak candidate cell: log of its chance
	std::vector<uint32_t> m_touched, m_cells, m_blocking, m_queue, m_region, m_component;
	std::vector<uint32_t> m_ringRays, m_ringEmpty;  ///< per ring of one cell around the sensor
	std::vector<uint32_t> m_binRays, m_binEmpty;
	double m_p11 = -1;
	double m_baseline = 0;
	double m_rangeEndMargin = 0;
	// One image row: 1 for each pixel that needs judging, and the depth at
	// which each ray meets the ground and the (fractional) grid cell it meets
	// there (see compute()).
	std::vector<uint8_t> m_rowCandidate;
	std::vector<float> m_rowT, m_rowCx, m_rowCy;
	// A statistics row: the frame cell of each pixel that is judged.
	std::vector<int32_t> m_rowCell;
};

}  // namespace gam
