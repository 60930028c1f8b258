// results.csv's schema (harness/results-schema.json): a row's setters write each column in its
// type or name the column, and a finished row fits or the run says which column does not.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "physbench/evaluate.h"
#include "physbench/runner.h"

namespace {

TEST(ResultsSchema, ARowSetterWritesItsColumnsTypeOrNamesTheColumn) {
  physbench::ResultRow row;
  row.exact("dt", 1.0 / 60.0);
  row.number("steps_per_s", std::nan(""));  // NaN: could not be computed, so empty
  row.integer("steps", 120);
  row.numbers("apex_rel_err", {0.5, std::nan(""), 1e-3}, 4);
  row.text("status", "ok");
  EXPECT_EQ(row["dt"], "0.016666666666666666");
  EXPECT_EQ(row["steps_per_s"], "");
  EXPECT_EQ(row["steps"], "120");
  EXPECT_EQ(row["apex_rel_err"], "0.5;;0.001");
  const std::vector<std::pair<std::function<void()>, std::string>> wrong = {
      {[&] { row.number("position_err_mx", 0.1); }, "position_err_mx is not in the schema"},
      {[&] { row.number("steps", 12.5); }, "steps is of type integer"},
      {[&] { row.text("dt", "fast"); }, "dt is of type number"},
      {[&] { row.integer("message", 1); }, "message is of type string"},
  };
  for (const auto& [set, why] : wrong) {
    try {
      set();
      ADD_FAILURE() << why << ": passed";
    } catch (const physbench::RunError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  }
}

// a row as the runner fills it for a finished job
std::map<std::string, std::string> fitting_row() {
  return {{"scenario", "projectile"}, {"engine", "rtp"},       {"variant", "rk4"},
          {"status", "ok"},           {"dt", "0.0166666667"}, {"duration", "2"},
          {"steps", "120"},           {"bodies", "1"},        {"steps_per_s_repeats", "1.2e+06;9e5"},
          {"tunnelled", "0"},         {"position_err_max", "inf"}, {"message", ""}};
}

TEST(ResultsSchema, ARowFitsOrTheRunSaysWhichColumnDoesNot) {
  EXPECT_NO_THROW(physbench::check_row(fitting_row()));
  const std::vector<std::tuple<std::string, std::string, std::string>> broken = {
      {"position_err_mx", "0.1", "position_err_mx is not in the schema"},  // a misspelt key
      {"status", "fine", "status holds 'fine', not a status"},
      {"dt", "", "dt is empty on a row that must fill it"},
      {"steps_per_s", "fast", "steps_per_s holds 'fast', not a number"},
      {"steps_per_s", "nan", "not a number"},  // NaN is written as an empty cell, never as text
      {"steps", "12.5", "steps holds '12.5', not a integer"},
      {"apex_rel_err", "0.1;x", "apex_rel_err holds '0.1;x', not a numbers"},
  };
  for (const auto& [column, value, why] : broken) {
    auto row = fitting_row();
    row[column] = value;
    try {
      physbench::check_row(row);
      ADD_FAILURE() << column << " = '" << value << "' passed";
    } catch (const physbench::RunError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("projectile rtp/rk4"), std::string::npos) << e.what();
    }
  }
}

}  // namespace

