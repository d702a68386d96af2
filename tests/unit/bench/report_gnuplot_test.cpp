#include <gtest/gtest.h>

#include "bench/report/gnuplot.hpp"

namespace calbench::report {
namespace {

TEST(ReportGnuplot, Base64KnownVectors) {
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64(std::string("\xff\x00\x10", 3)), "/wAQ");
}

TEST(ReportGnuplot, HtmlEscape) {
  EXPECT_EQ(html_escape("<a href=\"x\">O'Brien & co</a>"), "&lt;a href=&quot;x&quot;&gt;O&#39;Brien &amp; co&lt;/a&gt;");
}

TEST(ReportGnuplot, MakesAPngAndReportsScriptErrors) {
  const std::string png = run_gnuplot(
      "set terminal pngcairo size 200,100\nset output 'plot.png'\nplot 'd.dat' using 1:2 with lines\n",
      {{"d.dat", "0 0\n1 1\n2 4\n"}});
  ASSERT_GT(png.size(), 100u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_THROW(run_gnuplot("set output 'plot.png'\nthis is not gnuplot\n", {}), std::runtime_error);
}

}  // namespace
}  // namespace calbench::report
