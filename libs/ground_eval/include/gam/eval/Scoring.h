// Ground-aware mapping for MRPT -- map evaluation: scoring a map against the ground truth.
//
// Per-object detection by category, floor cells wrongly occupied, floor cells
// correctly free. Pure C++17, no MRPT.
//
// Rules (README "Map evaluator"):
//  * Every GT cell is compared with the map cells whose centres fall inside it (the
//    map may have another origin, extent or resolution). The worst one wins, as in
//    the GT's own probes: occupied if any is occupied, else free if any is free, else
//    unknown. When no map-cell centre falls inside (coarser map) the map is sampled at
//    the GT cell centre; outside the map = unknown.
//  * A map cell is occupied if p_occ > 0.5 + 1/255, free if p_occ < 0.5 - 1/255,
//    unknown otherwise (grey 127 and 128: the mapper writes 128 for "no evidence").
//    A second, stricter reading uses the yaml's occupied_thresh / free_thresh (how
//    map_server and a ROS planner read the map).
//  * An object counts if it has observed GT obstacle/drop cells; it is detected if at
//    least `min_hits` of them are occupied in the map. Its coverage = occupied /
//    observed cells.
//  * Floor = observed GT cells labelled free (plain floor, ramps, mats) farther than
//    `tolerance_cells` (Chebyshev) from any GT obstacle/drop cell, observed or not (an
//    unobserved cell of an object that is not a ramp counts as one of its obstacle or
//    drop cells: the GT file does not give an unobserved cell's label).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "gam/eval/MapReaders.h"

namespace gam::eval
{
enum class CellState : uint8_t
{
	Unknown,
	Free,
	Occupied
};

struct Options
{
	/** unknown band around p = 0.5 for the main reading (one grey level each side). */
	double unknown_tolerance = 1.0 / 255.0;
	/** floor cells closer than this (Chebyshev, cells) to a GT obstacle/drop cell,
	 * observed or not, are not scored. */
	int tolerance_cells = 1;
	/** occupied observed cells an object needs to count as detected. */
	int min_hits = 1;
};

/** The map read on the GT grid: per GT cell the highest and lowest p_occ of the map
 * cells whose centres are inside it (or the map at the GT cell centre); 0.5 outside. */
struct Resampled
{
	std::vector<float> pMax, pMin;
};
Resampled resample(const GroundTruth& gt, const RosMap& map);

/** Occupied if pMax > occ, else free if pMin < free, else unknown. */
std::vector<CellState> classify(const Resampled& r, double occThresh, double freeThresh);

struct ObjectScore
{
	int id = 0;
	std::string name, category;
	int observed = 0;  ///< observed GT obstacle/drop cells
	int occupied = 0, free = 0, unknown = 0;
	bool detected = false;
	double coverage() const { return observed ? double(occupied) / observed : 0.0; }
};

struct CategoryScore
{
	int objects = 0, detected = 0;
	double coverageSum = 0;  ///< sum of per-object coverage
	double detectionRate() const { return objects ? double(detected) / objects : 0.0; }
	double meanCoverage() const { return objects ? coverageSum / objects : 0.0; }
};

struct CellCounts
{
	long n = 0, occupied = 0, free = 0, unknown = 0;
	double pct(long v) const { return n ? 100.0 * double(v) / double(n) : 0.0; }
};

/** The scored floor cells of one ramp object (issue #13: a ramp must stay
 * free). Unknown = the simulator's noise-free ray reached the cell but the
 * map has no evidence there: the camera returned nothing (grazing dropouts on
 * a ramp's far side) or the cell was only ever at the edge of the view. */
struct RampScore
{
	int id = 0;
	std::string name;
	CellCounts cells;
	/** Free share of the cells the map knows (occupied or free) [%]. */
	double freeOfKnownPct() const
	{
		const long known = cells.occupied + cells.free;
		return known ? 100.0 * double(cells.free) / double(known) : 0.0;
	}
};

/** Scores of one map with one reading (thresholds). */
struct Reading
{
	std::string name;  ///< "p>0.5" or "map_server"
	double occ = 0.5, free = 0.5;
	std::vector<ObjectScore> objects;
	std::map<std::string, CategoryScore> categories;
	CellCounts floor;              ///< scored floor cells
	CellCounts ramp;               ///< the scored floor cells of category ramp
	std::vector<RampScore> ramps;  ///< the same per ramp object, by id
	CellCounts obstacle;           ///< observed GT obstacle/drop cells
};

struct MapScore
{
	std::string name, yamlPath;
	Reading main, strict;
	long excluded_floor = 0;  ///< observed free cells inside the tolerance band
};

/** Scores `map` against `gt`. */
MapScore evaluate(const GroundTruth& gt, const RosMap& map, const Options& opt = {});

}  // namespace gam::eval
