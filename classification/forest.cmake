# The per-pixel body-part forest (doc/forest.md): part of agex::classification. Boost.Iostreams
# (bzip2) reads PCL's compressed tree files; it is private to this module.
find_package(Boost REQUIRED COMPONENTS iostreams)
target_sources(agex_classification_lib PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/src/body_part_forest.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/pcl_tree_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/body_part_labeling.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/part_modes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/part_blobs.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/body_part_forest_trainer.cpp)
target_link_libraries(agex_classification_lib PRIVATE Boost::iostreams ${PCL_IO_LIBRARIES})
