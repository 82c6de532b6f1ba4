# The parsers of user input (scene files, models, views files, manifest lines) and the scene types they
# build, with nothing they do not call. The engine links them as a library of their own, and the
# fuzzers (tests/fuzz) compile the same list with their sanitizer flags: one list, so a parser that
# comes to call new code fails the ordinary build rather than the fuzz build in CI.
set(VKRAY_PARSER_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/typed_names.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/camera.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/gltf_json_shape.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/gltf_loader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/model_loader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/obj_loader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/ply_loader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/polygon_triangulation.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/scene_loader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene/text_lines.cpp
  ${CMAKE_CURRENT_LIST_DIR}/views/manifest_record.cpp
  ${CMAKE_CURRENT_LIST_DIR}/views/view_list.cpp)
