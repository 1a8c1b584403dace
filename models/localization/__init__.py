"""Robot localisation with the auxiliary particle filter (seed 002, section 1.3).

* :mod:`models.localization.model` - the robot (pose, odometry, Gaussian motion noise), the
  PCA + k-nearest-neighbour sensor model of eq. 1.14 with its outlier rule, and a
  range-bearing landmark sensor for real data;
* :mod:`models.localization.simulate` - a SIMULATED floor plan with perceptual aliasing and
  panoramic scans with occlusion outliers;
* :mod:`models.localization.mrclam` - the real UTIAS MRCLAM dataset 6;
* :mod:`models.localization.tracker` - a stateful localiser that validates its input, and
  offline helpers. The filters themselves are generic (:mod:`inference.particle`).
"""
