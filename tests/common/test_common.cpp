// libs/ground_common: the string helpers every library reads .ini values and
// text files with, the ground-truth label vocabulary, and the programs' one
// command-line behaviour (issue #30: code with no test of its own).
#include <gam/common/CommandLine.h>
#include <gam/common/GroundTruthLabels.h>
#include <gam/common/Strings.h>
#include <gtest/gtest.h>

#include <vector>

TEST(CommonStrings, TrimLowerAndCaseInsensitiveEquality)
{
	EXPECT_EQ(gam::trim("  K = 600 \t\r\n"), "K = 600");
	EXPECT_EQ(gam::trim(""), "");
	EXPECT_EQ(gam::trim(" \t "), "");
	EXPECT_EQ(gam::trim("x"), "x");
	EXPECT_EQ(gam::toLower("Ground_Aware N_th"), "ground_aware n_th");
	EXPECT_TRUE(gam::iequals("PAPER", "paper"));
	EXPECT_TRUE(gam::iequals("", ""));
	EXPECT_FALSE(gam::iequals("paper", "paper "));
	EXPECT_FALSE(gam::iequals("paper", "papers"));
}

TEST(CommonStrings, IniCommentsAreCutWhereMrptLeavesThem)
{
	// MRPT's reader keeps a trailing comment in the value; every key here is
	// read through stripIniComment.
	EXPECT_EQ(gam::stripIniComment("0.05   ; d_r [m]"), "0.05");
	EXPECT_EQ(gam::stripIniComment("true // 2D scans"), "true");
	EXPECT_EQ(gam::stripIniComment("paper # as printed"), "paper");
	EXPECT_EQ(gam::stripIniComment("  600  "), "600");
	EXPECT_EQ(gam::stripIniComment("; only a comment"), "");
	// The first of the three markers wins, whichever it is.
	EXPECT_EQ(gam::stripIniComment("1 # a ; b // c"), "1");
	EXPECT_EQ(gam::stripIniComment("1 // a # b"), "1");
	// A limitation, on purpose: a value cannot hold a marker (no key of this
	// project takes text with ';', '#' or '//').
	EXPECT_EQ(gam::stripIniComment("http://x"), "http:");
}

TEST(CommonLabels, NamesAndNumbersOfTheGroundTruthFiles)
{
	// The _gt_labels.csv vocabulary; the numbers are the PGM's label values.
	EXPECT_STREQ(gam::labelName(gam::GroundTruthLabel::Free), "free");
	EXPECT_STREQ(gam::labelName(gam::GroundTruthLabel::Obstacle), "obstacle");
	EXPECT_STREQ(gam::labelName(gam::GroundTruthLabel::Drop), "drop");
	EXPECT_STREQ(gam::labelName(gam::GroundTruthLabel::Unobserved), "unobserved");
	EXPECT_STREQ(gam::labelName(gam::GroundTruthLabel(7)), "?");
	EXPECT_EQ(int(gam::GroundTruthLabel::Free), 0);
	EXPECT_EQ(int(gam::GroundTruthLabel::Obstacle), 1);
	EXPECT_EQ(int(gam::GroundTruthLabel::Drop), 2);
	EXPECT_EQ(int(gam::GroundTruthLabel::Unobserved), 3);
}

namespace
{
struct Parsed
{
	int rc;
	std::string err;
	int n = -1;
};
Parsed parse(std::vector<std::string> args)
{
	TCLAP::CmdLine cmd("test program", ' ', "1.2.3");
	TCLAP::ValueArg<int> n("n", "number", "a number", false, 7, "N", cmd);
	std::vector<char*> argv;
	for (auto& a : args) argv.push_back(a.data());
	testing::internal::CaptureStderr();
	testing::internal::CaptureStdout();
	Parsed p;
	p.rc = gam::parseCommandLine(cmd, int(argv.size()), argv.data(), "prog");
	testing::internal::GetCapturedStdout();
	p.err = testing::internal::GetCapturedStderr();
	p.n = n.getValue();
	return p;
}
}  // namespace

TEST(CommonCommandLine, GoOnHelpVersionAndOneLineErrors)
{
	// Valid arguments: go on (-1), nothing printed.
	const Parsed ok = parse({"prog", "--number", "3"});
	EXPECT_EQ(ok.rc, -1);
	EXPECT_EQ(ok.n, 3);
	EXPECT_EQ(ok.err, "");
	// --help and --version: exit 0.
	EXPECT_EQ(parse({"prog", "--help"}).rc, 0);
	EXPECT_EQ(parse({"prog", "--version"}).rc, 0);
	// A parse error: exit 2 and exactly one line naming the argument.
	const Parsed bad = parse({"prog", "--number", "three"});
	EXPECT_EQ(bad.rc, 2);
	EXPECT_EQ(bad.err.rfind("prog: error: ", 0), 0u) << bad.err;
	EXPECT_NE(bad.err.find("number"), std::string::npos) << bad.err;
	EXPECT_NE(bad.err.find("(see --help)"), std::string::npos) << bad.err;
	EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
	const Parsed unknown = parse({"prog", "--nope"});
	EXPECT_EQ(unknown.rc, 2);
	EXPECT_EQ(std::count(unknown.err.begin(), unknown.err.end(), '\n'), 1) << unknown.err;
}
