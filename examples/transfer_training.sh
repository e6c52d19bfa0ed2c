# The transfer controller's training, shared by examples/evolve_regatta_transfer.sh,
# evolve_regatta_transfer_more.sh and evolve_regatta_transfer_final.sh (sourced, not run):
# each stage's training layouts as `--world` flags, in the order evolution reads them (the
# order is part of what makes a run reproducible), and the variations every trial draws. None
# of the layouts is one of the held-out worlds/regatta_heldout_*.wbt.

# Stage 1 (with the network's own world, thirteen layouts): the arenas of
# examples/evolve_regatta_varied.sh, two of other sizes, and five with every lamp lit.
transfer_stage1_worlds=(
  --world worlds/regatta_small.wbt --world worlds/regatta_wide.wbt
  --world worlds/regatta_offcentre.wbt --world worlds/regatta_four.wbt
  --world worlds/regatta_five.wbt
  --world worlds/regatta_train_compact.wbt --world worlds/regatta_train_broad.wbt
  --world worlds/regatta_train_lamps_regatta.wbt --world worlds/regatta_train_lamps_four.wbt
  --world worlds/regatta_train_lamps_five.wbt --world worlds/regatta_train_lamps_compact.wbt
  --world worlds/regatta_train_lamps_broad.wbt
)
# Stages 2 and 3: four more, lit buoys in 1.2 m arenas, a flat lit triangle, a 1.2 × 0.8 m arena.
transfer_stage2_worlds=(
  "${transfer_stage1_worlds[@]}"
  --world worlds/regatta_train_lamps_large3.wbt --world worlds/regatta_train_lamps_large5.wbt
  --world worlds/regatta_train_lamps_flat.wbt --world worlds/regatta_train_long.wbt
)
# Stages 4 and 5: two irregular quadrilaterals of four buoys in long arenas.
transfer_stage4_worlds=(
  "${transfer_stage2_worlds[@]}"
  --world worlds/regatta_train_long4.wbt --world worlds/regatta_train_lamps_narrow4.wbt
)
# Every trial: the arena's light (0.02 to 0.4, or off), each buoy's IR film and place, and
# the robot's start.
transfer_variations=(
  --vary 'DirectionalLight.intensity=0.02..0.4' --vary 'DirectionalLight.on=TRUE|FALSE'
  --vary 'Buoy.irReflectance=0.5|1' --vary 'Buoy.translation=±0.04'
  --vary 'Khepera.translation=arena' --vary 'Khepera.rotation=any'
)
