#include "io/machine/machine_file.h"

#include <gtest/gtest.h>

#include <random>

#include "io/common/io_error.h"
#include "test_support.h"

namespace tolver {
namespace {

TEST(MachineFile, MatsuuraTopologyAndParameterCount) {
  const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  ASSERT_EQ(m.model.axes.size(), 5u);
  std::vector<std::string> wp, tool;
  for (int a : m.model.workpiece_chain) wp.push_back(m.model.axes[a].name);
  for (int a : m.model.tool_chain) tool.push_back(m.model.axes[a].name);
  EXPECT_EQ(wp, (std::vector<std::string>{"Y", "X", "A", "C"}));
  EXPECT_EQ(tool, (std::vector<std::string>{"Z"}));
  // 5 x 6 link errors + 5 x 6 cubic series (4 coefficients) + 6 part + 6 tool.
  EXPECT_EQ(m.model.parameterCount(), 30 + 120 + 12);
  EXPECT_NEAR(m.model.axes[3].travel_min, -120 * M_PI / 180, 1e-15);
  EXPECT_EQ(m.model.axes[0].nc_sign, -1);
  EXPECT_EQ(m.model.parameters[m.model.findParameter("EYX.c2")].thesis_name, "e_y(X).c2");
  EXPECT_EQ(m.model.parameters[m.model.findParameter("gamma_z,X")].iso_code, "COX");
  EXPECT_TRUE(m.model.parameters[m.model.findParameter("BOC")].angular);
  EXPECT_EQ(m.model.findParameter("e_x,w"), m.model.findParameter("part.X"));
  EXPECT_TRUE(m.params.isZero());
}

TEST(MachineFile, Xkh800HasThe37TermsOfTable1) {
  const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[1]));
  EXPECT_EQ(m.model.aliases.size(), 37u);
  for (const auto& a : m.model.aliases) EXPECT_GE(a.parameter, 0);
  EXPECT_EQ(m.model.parameters[m.model.findParameter("dg_xy")].iso_code, "COY");
  EXPECT_EQ(m.model.blocks[m.model.parameters[m.model.findParameter("dx_x")].block].degree, 0);
}

TEST(MachineFile, ErrorValuesInTheirUnits) {
  const std::string xml = R"(<machine name="t" angle_unit="deg">
    <axis name="X" type="prismatic" branch="workpiece" direction="1 0 0" min="-100" max="100"/>
    <axis name="Y" type="prismatic" branch="workpiece" direction="0 1 0" min="-100" max="100"/>
    <axis name="Z" type="prismatic" branch="tool" direction="0 0 1" min="-100" max="100"/>
    <errors length_unit="um" angle_unit="urad" default_degree="2">
      <link axis="X" component="gz" value="12"/>
      <motion axis="Y" component="ex" coefficients="1 2 3 4 5"/>
      <setup frame="tool" component="ez" value="-7"/>
      <param name="EZX.c1" value="3"/>
    </errors></machine>)";
  const Machine m = parseMachineXml(xml, "t.xml");
  EXPECT_DOUBLE_EQ(m.params[m.model.findParameter("COX")], 12e-6);
  EXPECT_DOUBLE_EQ(m.params[m.model.findParameter("EXY.c4")], 5e-3);  // degree raised to 4
  EXPECT_EQ(m.model.findParameter("EYY.c3"), -1);                     // default degree 2
  EXPECT_DOUBLE_EQ(m.params[m.model.findParameter("tool.Z")], -7e-3);
  EXPECT_DOUBLE_EQ(m.params[m.model.findParameter("EZX.c1")], 3e-3);
}

// Writing and reading back gives the same model and values, for every shipped machine.
TEST(MachineFile, WriterRoundTripsEveryShippedMachine) {
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const char* file : test::shippedMachines()) {
    Machine m = readMachineFile(test::sourcePath(file));
    for (int i = 0; i < m.model.parameterCount(); i += 3)
      m.params[i] = n(rng) * (m.model.parameters[i].angular ? 1e-5 : 1e-3);
    const Machine back = parseMachineXml(formatMachineXml(m, "round trip"), "back.xml");
    ASSERT_EQ(back.model.parameterCount(), m.model.parameterCount()) << file;
    for (int i = 0; i < m.model.parameterCount(); ++i) {
      EXPECT_EQ(back.model.parameters[i].iso_code, m.model.parameters[i].iso_code);
      EXPECT_NEAR(back.params[i], m.params[i], 1e-15 + 1e-14 * std::abs(m.params[i]));
    }
    EXPECT_EQ(back.model.workpiece_chain, m.model.workpiece_chain);
    EXPECT_EQ(back.model.tool_chain, m.model.tool_chain);
    EXPECT_EQ(back.model.aliases.size(), m.model.aliases.size());
    EXPECT_EQ(back.model.preferred, m.model.preferred);
    for (size_t a = 0; a < m.model.axes.size(); ++a) {
      EXPECT_TRUE(
          back.model.axes[a].parent_T_joint.isApprox(m.model.axes[a].parent_T_joint, 1e-12));
      EXPECT_NEAR(back.model.axes[a].travel_max, m.model.axes[a].travel_max, 1e-12);
      EXPECT_EQ(back.model.axes[a].nc_sign, m.model.axes[a].nc_sign);
    }
  }
}

// The writer escapes what it writes: a name and a comment with XML's special characters (and a
// "--", which a comment may not hold) read back as written.
TEST(MachineFile, WriterEscapesNamesAndComments) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  m.model.name = "Cell <3> & \"A\" 'left'";
  const std::string xml = formatMachineXml(m, "from a <test> & more, run--1 -->");
  EXPECT_EQ(xml.find("--", xml.find("<!--") + 4), xml.find("-->"));  // no "--" inside the comment
  const Machine back = parseMachineXml(xml, "back.xml");
  EXPECT_EQ(back.model.name, m.model.name);
}

TEST(MachineFile, MalformedFilesNameLineAndField) {
  struct Case {
    const char* xml;
    int line;
    const char* field;
  };
  const Case cases[] = {
      {"<machine name='m'>\n<axis name='X' type='linear' branch='tool' direction='1 0 0' "
       "min='0' max='1'/></machine>",
       2, "axis.type"},
      {"<machine name='m'>\n\n<axis name='X' type='prismatic' branch='tool' direction='1 x 0' "
       "min='0' max='1'/></machine>",
       3, "axis.direction"},
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='5' max='1'/></machine>",
       2, "axis.max"},
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'/>\n<errors><link axis='Q' component='ex' value='1'/></errors></machine>",
       3, "link.axis"},
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'/>\n<errors><link axis='X' component='ew' value='1'/></errors></machine>",
       3, "link.component"},
      {"<machine name='m'>\n<axis name='X'", 2, "xml"},
      // Two prismatic axes along one line.
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'/>\n<axis name='Y' type='prismatic' branch='tool' direction='2 0 0' "
       "min='0' max='1'/></machine>",
       2, "axis.direction"},
      // Two axes at one order in a branch.
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' order='1' direction='1 0 "
       "0' "
       "min='0' max='1'/>\n<axis name='Y' type='prismatic' branch='tool' order='1' direction='0 1 "
       "0' "
       "min='0' max='1'/></machine>",
       3, "axis.order"},
      // A covariance that is not symmetric.
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'/>\n<identification_uncertainty>\n<covariance parameters='EXX.c1 EXX.c2'>"
       "<row>1 0.5</row><row>0.2 1</row></covariance></identification_uncertainty></machine>",
       4, "covariance"},
      // A count of readings an int cannot hold (1e300 was cast to int: undefined behaviour).
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'/>\n<identification_uncertainty readings='1e300'>\n<covariance "
       "parameters='EXX.c1'>"
       "<row>1</row></covariance></identification_uncertainty></machine>",
       3, "identification_uncertainty.readings"},
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'/>\n<identification_uncertainty readings='2.5'>\n<covariance "
       "parameters='EXX.c1'>"
       "<row>1</row></covariance></identification_uncertainty></machine>",
       3, "identification_uncertainty.readings"},
      // Absurd numbers (issue 17's policy): a link 1e300 mm away, a travel beyond 1e6 mm or 1e6
      // deg (an endless rotary axis may run many turns), any number beyond 1e9 in its own unit.
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'>\n<link translation='1e300 0 0'/></axis></machine>",
       3, "link.translation"},
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='0' max='1'>\n<link translation='2e6 0 0'/></axis></machine>",
       3, "link.translation"},
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1 0 0' "
       "min='-2e6' max='1'/></machine>",
       2, "axis.min"},
      {"<machine name='m'>\n<axis name='C' type='rotary' branch='tool' direction='0 0 1' "
       "min='0' max='2e6'/></machine>",
       2, "axis.max"},
      {"<machine name='m'>\n<axis name='X' type='prismatic' branch='tool' direction='1e10 0 0' "
       "min='0' max='1'/></machine>",
       2, "axis.direction"},
      {"<machine name='m'></machine>", 1, "axis"},
  };
  for (const Case& c : cases) {
    try {
      parseMachineXml(c.xml, "m.xml");
      ADD_FAILURE() << "accepted " << c.xml;
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), c.line) << e.what();
      EXPECT_EQ(e.field(), c.field) << e.what();
      EXPECT_EQ(e.file(), "m.xml");
    }
  }
}

}  // namespace
}  // namespace tolver
