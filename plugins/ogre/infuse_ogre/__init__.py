"""Ogre3D skeleton XML reader for infuse: bones, hierarchy, binding pose and animations."""
