// Ground-aware mapping for MRPT -- map evaluation against simulated ground truth.
//
// Scores a 2D occupancy map written in ROS map_server format (yaml + P5 pgm) against
// the ground truth of gam-simulate: per-object detection by category, floor cells
// wrongly occupied, floor cells correctly free. Pure C++17, no MRPT.
//
// This header includes the whole evaluator, one header per job:
//  * MapReaders.h: reading the map_server map and the ground truth (loadRosMap,
//    loadGroundTruth, Error);
//  * Scoring.h: the scoring rules (resample, classify, evaluate and the scores);
//  * Reports.h: the reports (formatTable, toJson, toCsv);
//  * Sequence.h: the maps after every frame against the per-frame ground truth
//    (ghost cells, time to clear, hazards out of view, changes outside the view).
#pragma once

#include "gam/eval/MapReaders.h"
#include "gam/eval/Reports.h"
#include "gam/eval/Scoring.h"
#include "gam/eval/Sequence.h"
