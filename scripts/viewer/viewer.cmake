# The viewer bundle of the HTML reports (scripts/viewer/build.mjs), compiled into the
# export stage (stages/export/export_html.c), which writes it into every published item.
# Included by stages/CMakeLists.txt. The bundle is built from the npm packages pinned by
# scripts/viewer/package-lock.json (npm ci --prefix scripts/viewer: scripts/install-deps.sh);
# build.mjs runs on every build and rewrites its outputs only when their bytes change, so
# a later `npm ci` is picked up without reconfiguring. Without node the export stage is
# built with no bundle, and without the packages build.mjs gives an empty one: the pages
# then have no 3D views (tests/export/test_html_report.sh fails, saying so).
find_program(SCANLOD_NODE node)
if(SCANLOD_NODE)
  set(SCANLOD_VIEWER_JS ${PROJECT_BINARY_DIR}/viewer/scanlod-viewer.js)
  set(SCANLOD_VIEWER_C ${PROJECT_BINARY_DIR}/viewer/viewer_bundle.c)
  add_custom_target(sl_viewer_bundle
    COMMAND ${SCANLOD_NODE} ${PROJECT_SOURCE_DIR}/scripts/viewer/build.mjs
            ${SCANLOD_VIEWER_JS} ${SCANLOD_VIEWER_C}
    BYPRODUCTS ${SCANLOD_VIEWER_JS} ${SCANLOD_VIEWER_C}
    COMMENT "Report viewer bundle (scripts/viewer/build.mjs)"
    VERBATIM)
  target_sources(sl_stages PRIVATE ${SCANLOD_VIEWER_C})
  target_compile_definitions(sl_stages PRIVATE SCANLOD_VIEWER=1)
  add_dependencies(sl_stages sl_viewer_bundle)
else()
  message(WARNING "node not found: the HTML reports get no 3D views (scripts/install-deps.sh)")
endif()
