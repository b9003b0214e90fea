# Embeds the viewer page include/handemo/render/viewer_page.html as a C++ string: writes
# <out>/handemo/render/viewer_page.hpp, which render/viewer.hpp includes. The top-level CMakeLists.txt includes
# this file at configure time (out: the build tree's generated/ folder; a change to the page re-runs it);
# `cmake -DHANDEMO_SOURCE=<source dir> -DHANDEMO_GENERATED=<dir> -P cmake/embed_viewer_page.cmake` does the same
# for a build without the project (bench/compile_time.sh).
if(CMAKE_SCRIPT_MODE_FILE)
  set(_handemo_src ${HANDEMO_SOURCE})
  set(_handemo_out ${HANDEMO_GENERATED})
else()
  set(_handemo_src ${PROJECT_SOURCE_DIR})
  set(_handemo_out ${PROJECT_BINARY_DIR}/generated)
endif()
set(_handemo_page ${_handemo_src}/include/handemo/render/viewer_page.html)
file(READ ${_handemo_page} HANDEMO_VIEWER_PAGE)
string(FIND "${HANDEMO_VIEWER_PAGE}" ")handemo_page\"" _handemo_end)
if(NOT _handemo_end EQUAL -1)
  message(FATAL_ERROR "${_handemo_page} contains the raw-string delimiter )handemo_page\"")
endif()
configure_file(${_handemo_src}/cmake/viewer_page.hpp.in ${_handemo_out}/handemo/render/viewer_page.hpp @ONLY)
