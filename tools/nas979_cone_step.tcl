pload ALL
# The NAS 979 cone frustum of samples/nas979_cone.stl as a B-rep: base radius 40 mm at z = 0,
# 15 deg half-angle, 40 mm high, on a 100 x 100 x 10 mm plate (tools/make_samples.cpp).
set R1 [expr 40.0 - 40.0*tan(15.0*acos(-1)/180.0)]
pcone c 40 $R1 40
box b -50 -50 -10 100 100 10
bfuse r b c
explode r F
XNewDoc D
XAddShape D r 0
XSetColor D r_7 0.8 0.2 0.2
XSetColor D r_8 0.2 0.4 0.8
param write.step.schema 4
param write.step.unit MM
# Run from samples/: occt-draw -b -f ../tools/nas979_cone_step.tcl
WriteStep D nas979_cone.step
exit
