# The independent figures of tests/step_file_test.cpp: run `occt-draw -b -f reference.tcl` here.
# Draw reads each file through STEPControl (no XCAF, no tessellation) and prints its face count,
# its area (sprops, adaptive to 1e-7) and its optimal bounding box (Draw widens it by 1e-7).
pload ALL
foreach f {face_recognition_sample_part.stp transmission_pulley_at3_t10_center.STEP
           nist_ctc_01_asme1_ap242-e1.stp Ventilator.stp 11752.stp} {
  stepread $f a *
  puts "$f: [nbshapes a_1]"
  puts [sprops a_1 1e-7]
  puts "box [bounding -optimal a_1]"
}
# Assemblies: one part, by its label (Xdump D shows the tree).
ReadStep D as1_pe_203.stp
XGetShape s D 0:1:1:7
puts "as1_pe_203.stp L-BRACKET: [nbshapes s]"
puts [sprops s 1e-7]
ReadStep E as1-oc-214.stp
XGetShape r E 0:1:1:4
puts "as1-oc-214.stp rod: [nbshapes r]"
puts [sprops r 1e-7]
exit
