# Writes every tolver library's and the CLI's direct links, one target a line
# ("target: dep;dep"), to ${CMAKE_BINARY_DIR}/tolver_links.txt, for tests/check_layers.sh: a
# target that links a layer above it fails the test (ARCHITECTURE.md gives the order).
function(tolver_write_layer_links)
  set(targets tolver_core_numerics tolver_core_model tolver_core_kinematics tolver_core_path
              tolver_core_calibration tolver_core_diagnosis tolver_core_allocation tolver_core
              tolver_geometry tolver_io tolver_pipeline tolver)
  set(text "")
  foreach(t ${targets})
    get_target_property(type ${t} TYPE)
    if(type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(libs ${t} INTERFACE_LINK_LIBRARIES)
    else()
      get_target_property(libs ${t} LINK_LIBRARIES)
    endif()
    if(NOT libs)
      set(libs "")
    endif()
    # Aliases (tolver::io) by their target's name; generator expressions of private links
    # ($<LINK_ONLY:...>) reduced to the target.
    set(names "")
    foreach(l ${libs})
      string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" l "${l}")
      if(TARGET ${l})
        get_target_property(aliased ${l} ALIASED_TARGET)
        if(aliased)
          set(l ${aliased})
        endif()
      endif()
      list(APPEND names ${l})
    endforeach()
    string(APPEND text "${t}: ${names}\n")
  endforeach()
  file(WRITE ${CMAKE_BINARY_DIR}/tolver_links.txt "${text}")
endfunction()
