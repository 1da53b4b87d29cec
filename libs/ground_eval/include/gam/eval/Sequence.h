// Ground-aware mapping for MRPT -- map evaluation over time (issue #14).
//
// Scores the maps of a mapper run after every frame (ground-aware-mapper
// --snapshot-every: DIR/snapshots/NNNNNN/<label>.yaml + index.csv) against the
// simulator's per-frame ground truth (PREFIX_gt_frames.csv: per frame the rawlog
// entries, the cells whose geometric label changed, the cells each depth camera saw,
// the cells its measured points fell into and the cells the Leddar's beams swept).
// Pure C++17, no MRPT.
//
// Rules (doc/benchmark.md "Over time"), per GT cell, frames 0..F-1, map state as in
// Scoring.h (occupied p > 0.5 + 1/255, free p < 0.5 - 1/255):
//  * seen: in the frame's depth-camera footprint (`view` runs). The Leddar's beams
//    (`leddar` runs) and the cells of the measured, noisy points (`points` runs: flying
//    pixels, spikes) count only for "changed outside the view".
//  * Former obstacle cell: seen as GT obstacle in some frame, later seen as GT free
//    (first frame s), farther than `tolerance_cells` from any current GT
//    obstacle/drop, and occupied in the map after frame s-1: the map has something
//    to clear. Time to clear = first frame f >= s with the cell not occupied, minus
//    s. Ghost = still occupied after frame s + ghost_frames (cells with s +
//    ghost_frames beyond the last frame are not judged; a cell seen as obstacle
//    again before being cleared is dropped).
//  * Hazard cell: GT drop cell occupied in the map after the last frame in which it
//    was in view (seen, or within view_margin_cells of the footprint). In every later
//    frame in which it is still GT drop, out of view (farther than view_margin_cells
//    from the footprint) and inside the map's extent, it must stay occupied; a cell
//    that is not, in any such frame, is lost (changes while it is in view are the
//    detection's business, not this rule's).
//  * Changed outside the view: the map state (occupied / free / unknown) of a cell
//    differs from the one after the previous frame (frame 0: from unknown), the cell
//    is inside both maps' extents and farther than view_margin_cells from the
//    frame's camera footprints, measured points and Leddar beams. Value changes = any change of the
//    grey level, counted the same way.
//  * Per frame: GT obstacle/drop cells seen so far with their label of this frame:
//    occupied share; floor = cells seen so far, GT free now, farther than
//    tolerance_cells from a GT obstacle/drop of this frame: occupied and free shares.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "gam/eval/MapReaders.h"
#include "gam/eval/Scoring.h"

namespace gam::eval
{
/** Cells ix0..ix1 of row iy. */
struct CellRun
{
	int iy = 0, ix0 = 0, ix1 = 0;
	Label label = Label::Free;  ///< geom runs only
	int objectId = 0;           ///< geom runs only
};

struct FrameTruth
{
	long firstEntry = -1, lastEntry = -1;  ///< the rawlog entries of this frame
	std::vector<CellRun> geom;             ///< cells whose geometric label changed (frame 0: every non-free cell)
	std::vector<CellRun> view;             ///< seen by a depth camera (true, noise-free footprint)
	std::vector<CellRun> points;           ///< holding a measured (noisy) depth point
	std::vector<CellRun> leddar;           ///< swept by the Leddar's beams
};

struct SequenceTruth
{
	std::vector<FrameTruth> frames;
};

/** Reads PREFIX_gt_frames.csv (frame,kind,iy,ix0,ix1,label,object_id); the cells must
 * be on `gt`'s grid, frames 0..F-1 each with one entries row. Throws Error. */
SequenceTruth loadSequenceTruth(const std::string& prefix, const GroundTruth& gt);

/** One row of DIR/snapshots/index.csv. */
struct SnapshotRow
{
	std::string name;  ///< folder under DIR/snapshots
	long frames = 0, frameIndex = 0, rawlogEntry = 0;
};
/** Reads MAPDIR/snapshots/index.csv. Throws Error. */
std::vector<SnapshotRow> loadSnapshotIndex(const std::string& mapDir);

/** For every frame of `seq`, the snapshot taken after its last rawlog entry (its
 * folder name). Throws Error naming the first frame without one. */
std::vector<std::string> snapshotsPerFrame(const SequenceTruth& seq, const std::vector<SnapshotRow>& index);

struct SequenceOptions
{
	int ghost_frames = 10;      ///< ghost = still occupied this many frames after seen free
	int tolerance_cells = 1;    ///< as Options::tolerance_cells (Chebyshev)
	int view_margin_cells = 1;  ///< cells this close to a footprint count as in view
	double unknown_tolerance = 1.0 / 255.0;
};

struct FrameScore
{
	int frame = 0;
	long obstacle_cells = 0, obstacle_occupied = 0;  ///< seen so far, GT obstacle/drop now
	long floor_cells = 0, floor_occupied = 0, floor_free = 0;
	long to_clear = 0;              ///< former obstacle cells seen free, still occupied after this frame
	long ghost_cells = 0;           ///< of them: seen free >= ghost_frames frames ago
	long hazard_out_of_view = 0;    ///< hazard cells out of view in this frame
	long hazard_lost = 0;           ///< of them: not occupied
	long changed_outside_view = 0;  ///< cells whose state changed in this frame outside the view
	long value_changed_outside_view = 0;
};

struct SequenceScore
{
	std::string name;
	int frames = 0;
	long former_obstacle_cells = 0;  ///< cells the map had to clear
	long ghost_judged = 0;           ///< of them: with ghost_frames frames left to judge
	long ghost_cells = 0;            ///< of the judged: still occupied ghost_frames frames after seen free
	std::vector<int> clear_frames;   ///< per cleared cell: frames from seen free to not occupied
	long not_cleared = 0;            ///< never cleared until the last frame
	long hazard_cells = 0;           ///< hazard cells (occupied when last seen) out of view in some frame
	long hazard_lost = 0;            ///< of them: not occupied in such a frame
	long changed_outside_view = 0;   ///< cell-frame events
	long changed_outside_cells = 0;  ///< distinct cells
	long value_changed_outside_view = 0;
	std::vector<FrameScore> perFrame;

	double ghostPct() const { return ghost_judged ? 100.0 * double(ghost_cells) / double(ghost_judged) : 0.0; }
	/** Median / maximum of clear_frames (-1 if none). */
	double medianClearFrames() const;
	int maxClearFrames() const;
};

/** Scores one map's sequence; `snapshot(f)` returns the map after frame f (called
 * once per frame, in order). */
SequenceScore evaluateSequence(
	const GroundTruth& gt, const SequenceTruth& seq, const std::function<RosMap(int)>& snapshot,
	const SequenceOptions& opt = {});

/** Text table of several maps. */
std::string formatSequenceTable(const std::vector<SequenceScore>& s, const SequenceOptions& opt);
/** JSON document with every number (per-frame arrays included). */
std::string sequenceToJson(const std::vector<SequenceScore>& s, const SequenceOptions& opt);
/** Per-frame CSV: map,frame,obstacle_cells,obstacle_occupied,floor_cells,floor_occupied,
 * floor_free,to_clear,ghost_cells,hazard_out_of_view,hazard_lost,changed_outside_view,
 * value_changed_outside_view. */
std::string sequenceToCsv(const std::vector<SequenceScore>& s);

}  // namespace gam::eval
