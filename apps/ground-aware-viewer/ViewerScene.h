// Ground-aware mapping for MRPT -- ground-aware-viewer, the GUI-free scenes.
//
// ViewerScene: what to draw for each view of a ViewerModel (point cloud, 2.5D
// voxels, ground plane patch, RRT tree, grids as textured planes) as
// mrpt::opengl scenes, and off-screen rendering to PNG with CFBORender (no
// display needed). Used by the wx GUI (ViewerApp.cpp), its batch mode and
// tests/viewer.
#pragma once

#include <mrpt/opengl/CCamera.h>
#include <mrpt/opengl/COpenGLScene.h>

#include <string>
#include <vector>

#include "ViewerModel.h"

namespace gam::viewer
{
enum class View
{
	Frame3D,          ///< current step: point cloud, 2.5D voxels by class, ground plane, RRT tree
	Map3D,            ///< accumulated 2.5D map (columns), point cloud of all frames, ground-aware grid below, path
	Grids,            ///< the three grids side by side (top view)
	GridGroundAware,  ///< one grid, top view
	GridHeightBand,
	GridOctomap
};
const char* viewName(View v);  ///< file stem: frame, map, grids, grid_ground_aware, ...
std::vector<View> allViews();

/** The xy box the grid views show: the observed part of the ground-aware grid
 * plus a margin (or the robot +- 3 m before anything is observed). */
struct Box
{
	double x0 = -3, x1 = 3, y0 = -3, y1 = 3;
	double w() const { return x1 - x0; }
	double h() const { return y1 - y0; }
};
Box gridViewBox(const ViewerModel& m);

class ViewerScene
{
   public:
	/** Fills `scene` (cleared first) and sets `cam` for the view; `aspect` =
	 * image width / height (for the top views' zoom). */
	static void build(
		const ViewerModel& m, View v, mrpt::opengl::COpenGLScene& scene, mrpt::opengl::CCamera& cam, double aspect);
	/** Pixel (column, row from the top) of world point (x, y) in a W x H
	 * rendering of a single-grid top view. */
	static void gridPixel(const ViewerModel& m, double x, double y, int W, int H, double& col, double& row);
	/** Renders with CFBORender (off-screen, EGL: no display needed) into a PNG. */
	static void renderToPng(const ViewerModel& m, View v, const std::string& file, int W = 800, int H = 600);
};

}  // namespace gam::viewer
