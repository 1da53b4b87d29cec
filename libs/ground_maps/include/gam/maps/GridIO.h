// Ground-aware mapping for MRPT
// Writers (and small readers, for tests and tools) of the 2D-grid outputs of
// ground-aware-mapper: ROS map_server YAML + PGM, .gridmap.gz, PNG.
#pragma once

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/serialization/CSerializable.h>

#include <cstdint>
#include <string>
#include <vector>

namespace gam::maps
{
/** PGM grey level of a cell: round(255 * (1 - p_occupied)) = round(255 * p_free),
 * p_free = COccupancyGridMap2D::l2p(cell). */
uint8_t pgmValue(mrpt::maps::COccupancyGridMap2D::cellType cell);

/** Writes `<pgmPath>` (binary P5, first row = highest y) and `<yamlPath>`
 * (ROS map_server: image = `imageName`, mode scale, negate 0, origin = lower-left
 * corner). Throws std::runtime_error on I/O errors. */
void writeRosMap(
	const mrpt::maps::COccupancyGridMap2D& grid, const std::string& yamlPath, const std::string& pgmPath,
	const std::string& imageName);

/** A plain COccupancyGridMap2D copy of `grid` (also of derived classes),
 * gzip-serialized: stock MRPT reads it with
 * `archiveFrom(CFileGZInputStream(f)) >> COccupancyGridMap2D`. */
void writePlainGridmapGz(const mrpt::maps::COccupancyGridMap2D& grid, const std::string& path);

/** The part of a grid a PNG shows: cells [cx0, cx0+w) x [cy0, cy0+h), each
 * drawn as scale x scale pixels; pixel (px, py) shows cell
 * (cx0 + px/scale, cy0 + h-1 - py/scale) (+y up). */
struct PngView
{
	int cx0 = 0, cy0 = 0, w = 0, h = 0, scale = 1;
};
/** The bounding box of the observed cells (log-odds != 0) plus 1 m, clamped to
 * the grid (the whole grid if nothing was observed), scaled up by an integer
 * factor (<= 8) towards ~600 px. */
PngView pngViewOf(const mrpt::maps::COccupancyGridMap2D& grid);

/** How writeGridPng() draws. */
struct PngStyle
{
	/** A 1 m scale bar and a legend (free, occupied, unknown, and missing
	 * floor when `missing` is set) in a strip below the map. */
	bool legend = false;
	/** A missing-floor layer of the same geometry (CGroundAwareOccupancyGrid::
	 * missingFloorLayer()): its missing cells are drawn orange. */
	const mrpt::maps::COccupancyGridMap2D* missing = nullptr;
};

/** RGB picture of pngViewOf(grid): grey = the PGM value of the cell; cells never
 * observed (log-odds exactly 0) are light blue (kUnknown*). */
void writeGridPng(const mrpt::maps::COccupancyGridMap2D& grid, const std::string& path, const PngStyle& style = {});
constexpr uint8_t kUnknownR = 190, kUnknownG = 205, kUnknownB = 235;
constexpr uint8_t kMissingR = 255, kMissingG = 140, kMissingB = 0;

/** `to` takes the extent, resolution and cells of `from`; its options stay. */
void copyGridCells(const mrpt::maps::COccupancyGridMap2D& from, mrpt::maps::COccupancyGridMap2D& to);

/** A plain copy (slices a derived grid). */
mrpt::maps::COccupancyGridMap2D plainCopy(const mrpt::maps::COccupancyGridMap2D& grid);

/** `obj` serialized into a gzip file (MRPT's archive format: stock tools read
 * it with archiveFrom(CFileGZInputStream(path)) >> obj). Throws std::runtime_error. */
void writeSerializedGz(const mrpt::serialization::CSerializable& obj, const std::string& path);
/** Crops / extends `grid` to a window of n x n cells centred on (cx, cy),
 * keeping the cell alignment and the log-odds of the cells inside; new cells
 * are unknown. Returns true if the grid changed. */
bool recentreGrid(mrpt::maps::COccupancyGridMap2D& grid, double cx, double cy, int n);

// --------------------------------------------------------------- readers
// (map_server yaml + PGM: gam::eval::loadRosMap in libs/ground_eval.)

/** Reads a .gridmap / .gridmap.gz as a stock COccupancyGridMap2D, exactly as
 * a stock MRPT tool does (`archive >> COccupancyGridMap2D`): a file holding a
 * derived class (a serialized CGroundAwareOccupancyGrid) is refused. */
mrpt::maps::COccupancyGridMap2D readGridmapGz(const std::string& path);

/** Reads any stock grid file into a plain COccupancyGridMap2D:
 * - `*.yaml`: a ROS map_server map (COccupancyGridMap2D::loadFromROSMapServerYAML:
 *   `mode: scale` reads each pixel as P(free), `trinary` by the thresholds);
 * - anything else (`.gridmap`, `.gridmap.gz`): one serialized COccupancyGridMap2D
 *   or any class derived from it (its COccupancyGridMap2D part).
 * Throws std::runtime_error naming the file and what is wrong with it. */
mrpt::maps::COccupancyGridMap2D readStockGrid(const std::string& path);

}  // namespace gam::maps
