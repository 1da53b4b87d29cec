// Ground-aware mapping for MRPT -- map evaluation: the inputs.
//
// Readers of the two inputs of the evaluator: a 2D occupancy map in ROS map_server
// format (yaml + P5 pgm) and the ground truth of gam-simulate (PREFIX_gt.yaml,
// PREFIX_gt_labels.csv, PREFIX_gt_objects.csv). Pure C++17, no MRPT.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>
#include "gam/common/GroundTruthLabels.h"

namespace gam::eval
{
/** Every input problem (missing file, bad header, bad value). */
struct Error : std::runtime_error
{
	using std::runtime_error::runtime_error;
};

/** A ROS map_server map: yaml keys + the image (row 0 = highest y). */
struct RosMap
{
	std::string yamlPath, imagePath, mode = "trinary";
	double resolution = 0, origin_x = 0, origin_y = 0, origin_yaw = 0;
	int negate = 0;
	double occupied_thresh = 0.65, free_thresh = 0.196;
	int width = 0, height = 0;
	std::vector<uint8_t> pixels;

	/** p_occupied of cell (col, row from the bottom); mode scale/trinary and negate
	 * applied (trinary: 1, 0 or 0.5). */
	double pOcc(int col, int rowFromBottom) const;
	bool inside(int col, int rowFromBottom) const
	{
		return col >= 0 && rowFromBottom >= 0 && col < width && rowFromBottom < height;
	}
};

/** Reads the yaml (image, resolution, origin, mode, negate, thresholds) and its P5
 * pgm (maxval 255; the image path is relative to the yaml's folder). Throws Error. */
RosMap loadRosMap(const std::string& yamlPath);

using Label = gam::GroundTruthLabel;
using gam::labelName;

struct GtObject
{
	int id = 0;
	std::string name, type, category;
};

struct GroundTruth
{
	std::string prefix;
	double resolution = 0;
	int nx = 0, ny = 0;
	// per cell, index iy * nx + ix
	std::vector<double> x, y;  ///< cell centres
	std::vector<Label> label;
	std::vector<int> objectId;
	std::vector<GtObject> objects;

	size_t idx(int ix, int iy) const { return size_t(iy) * size_t(nx) + size_t(ix); }
	const GtObject* object(int id) const;
};

/** Reads PREFIX_gt.yaml (resolution), PREFIX_gt_labels.csv and PREFIX_gt_objects.csv.
 * Throws Error. */
GroundTruth loadGroundTruth(const std::string& prefix);

}  // namespace gam::eval
