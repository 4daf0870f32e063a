//! Blur shells for deforming meshes (Jones and Keyser): silhouette of motion, history rings, hysteresis, fading.
