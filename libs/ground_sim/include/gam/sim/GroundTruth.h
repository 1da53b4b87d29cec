// Ground-aware mapping for MRPT -- scene simulator: ground-truth 2D grid.
//
// Label rules (per cell; each cell is probed at subsamples x subsamples
// points spread over it, and the worst probe wins: obstacle > drop > free):
//  * support level g at a probe = 0 (floor), or -depth inside a pit; solids
//    whose top is at or below obstacle_min_height (steps inside a stairwell)
//    raise g to their top; traversable ramps (slope <= max_slope_deg) raise g
//    to their surface and are never obstacles.
//  * obstacle: a non-traversable solid occupies part of the vertical band
//    (g + obstacle_min_height, robot_height) above the probe. Parts entirely
//    above robot_height (e.g. a high shelf board) do not count.
//  * drop: no obstacle and g < -drop_min_depth (holes, outlets, stairwells,
//    bottomless pits).
//  * obstacle too: a step inside a cell that is otherwise free, i.e. the
//    support level g of its free probes varies by more than
//    obstacle_min_height (probed on (subsamples + 1)^2 points that include
//    the cell's edges): the side face of a raised ramp, the end of a plateau
//    without a back slope. Object: the higher support (the ramp).
//  * free: otherwise (floor, ramps).
//  * unobserved: the cell received no point of any frame's geometric visible
//    footprint (see DepthFrame::footprint); this replaces the label (the
//    geometric label stays available in `geomLabel`).
// Object id per cell: the object causing the label (obstacle/drop), the ramp
// for ramp cells, 0 for plain floor.
// Categories are per object (written in the objects list, repeated per cell):
//  * negative: holes and downward stairs;
//  * ramp: traversable slopes;
//  * overhang: some part of the object has its underside higher than
//    overhang_clearance above the floor (table tops, shelf boards);
//  * small: otherwise, if the object's top is lower than small_max_height;
//  * large: otherwise. A `category=` key in the scene overrides this.
#pragma once

#include <vector>
#include "gam/common/GroundTruthLabels.h"

#include "gam/sim/Scene.h"

namespace gam::sim
{
using Label = gam::GroundTruthLabel;
using gam::labelName;

struct GridSpec
{
	double resolution = 0.05;
	double min_x = -1, max_x = 5, min_y = -3, max_y = 3;
	double robot_height = 1.90;         ///< walker + user: overhangs below it block
	double obstacle_min_height = 0.02;  ///< smallest bump that counts [m]
	double drop_min_depth = 0.02;       ///< smallest drop that counts [m]
	double small_max_height = 0.20;
	double overhang_clearance = 0.10;
	double max_slope_deg = 10.0;
	int subsamples = 3;
	int nx() const;
	int ny() const;
	double cellX(int ix) const { return min_x + (ix + 0.5) * resolution; }
	double cellY(int iy) const { return min_y + (iy + 0.5) * resolution; }
};

class GroundTruthGrid
{
   public:
	GridSpec spec;
	std::vector<Label> geomLabel;  ///< from geometry only
	std::vector<int> objectId;
	std::vector<uint8_t> observed;

	/** Computes the geometric labels and sets the object categories in
	 * `scene.objects` (unless given in the scene). */
	void build(Scene& scene, const GridSpec& s);
	/** Labels the cells of `region` (xy, plus one cell around it) again from `scene`
	 * (e.g. Scene::atFrame(f) after an object moved; build() must have run). */
	void relabel(const Scene& scene, const Eigen::AlignedBox2d& region);
	/** Marks the cells containing the given world points as observed. */
	void markObserved(const std::vector<Eigen::Vector2d>& pts);
	/** Final label (unobserved where never seen). */
	Label label(int ix, int iy) const;
	Label labelAt(double x, double y) const;
	int objectAt(double x, double y) const;
	bool cellOf(double x, double y, int& ix, int& iy) const;
	size_t idx(int ix, int iy) const { return size_t(iy) * size_t(spec.nx()) + size_t(ix); }

	/** Labels one cell from its subsamples x subsamples probes (the worst wins). */
	void labelCell(const Scene& scene, int ix, int iy);
	/** Geometric probe at one point: label and object id (and, if asked, the
	 * support level g there). */
	static Label probe(const Scene& scene, const GridSpec& s, double x, double y, int& obj, double* support = nullptr);
};

}  // namespace gam::sim
