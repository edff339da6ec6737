"""Registers the built-in BML behaviour handlers: one component per element family."""
from __future__ import annotations

import infuse
from infuse.plugin_types import BMLBehaviour

from . import face, gaze, gesture, head, locomotion, manipulation, misc, posture, speech


def _component(name, factory, elements, attributes, description):
    return BMLBehaviour(name, factory, description, tuple(elements), frozenset(attributes))


@infuse.hookimpl
def infuse_bml_behaviours():
    return [
        _component("speech", speech.plan, ["speech"], speech.ATTRIBUTES, "speech with inline sync marks"),
        _component("gaze", gaze.plan_gaze, ["gaze"], gaze.ATTRIBUTES, "temporary gaze at a target"),
        _component("gazeShift", gaze.plan_gaze_shift, ["gazeShift"], gaze.ATTRIBUTES, "lasting change of gaze"),
        _component("headDirectionShift", gaze.plan_head_direction_shift, ["headDirectionShift"], gaze.ATTRIBUTES,
                   "lasting change of head direction"),
        _component("head", head.plan, ["head"], head.ATTRIBUTES, "nod, shake, toss, tilt and other head movements"),
        _component("faceLexeme", face.plan_lexeme, ["faceLexeme"], face.LEXEME_ATTRIBUTES, "facial expression by name"),
        _component("faceShift", face.plan_shift, ["faceShift"], face.LEXEME_ATTRIBUTES,
                   "lasting change of facial expression"),
        _component("faceFacs", face.plan_facs, ["faceFacs"], face.FACS_ATTRIBUTES, "FACS action unit"),
        _component("face", face.plan_face, ["face"], face.FACE_ATTRIBUTES, "SmartBody and draft <face>"),
        _component("posture", posture.plan_posture, ["posture"], posture.POSTURE_ATTRIBUTES, "temporary posture"),
        _component("postureShift", posture.plan_posture_shift, ["postureShift"], posture.POSTURE_ATTRIBUTES,
                   "lasting posture change"),
        _component("body", posture.plan_body, ["body"], posture.BODY_ATTRIBUTES, "SmartBody idle posture"),
        _component("torso", posture.plan_torso, ["greta:torso", "torso"], posture.TORSO_ATTRIBUTES, "Greta torso lexeme"),
        _component("gesture", gesture.plan_gesture, ["gesture"], gesture.GESTURE_ATTRIBUTES, "gesture clip"),
        _component("pointing", manipulation.plan_pointing, ["pointing"], manipulation.POINTING_ATTRIBUTES,
                   "point at a target"),
        _component("animation", gesture.plan_animation, ["animation", "sbm:animation"], gesture.ANIMATION_ATTRIBUTES,
                   "play a named clip"),
        _component("blend", gesture.plan_blend, ["blend", "sbm:blend"], gesture.BLEND_ATTRIBUTES,
                   "SmartBody parameterized blend"),
        _component("locomotion", locomotion.plan, ["locomotion", "sbm:locomotion"], locomotion.ATTRIBUTES,
                   "walk, jog or run to a target or along a path"),
        _component("reach", manipulation.plan_reach, ["sbm:reach", "reach"], manipulation.REACH_ATTRIBUTES,
                   "reach to touch, pick up, put down or point at"),
        _component("grab", manipulation.plan_grab, ["sbm:grab", "grab"], manipulation.GRAB_ATTRIBUTES, "grasp an object"),
        _component("touch", manipulation.plan_touch, ["touch", "sbm:touch"], manipulation.TOUCH_ATTRIBUTES,
                   "touch a target"),
        _component("ik-constraint", manipulation.plan_constraint, ["sbm:constraint"], manipulation.CONSTRAINT_ATTRIBUTES,
                   "hold an effector on a target"),
        _component("wait", misc.plan_wait, ["wait"], misc.WAIT_ATTRIBUTES, "a pause other behaviours can align to"),
        _component("event", misc.plan_event, ["event", "sbm:event"], misc.EVENT_ATTRIBUTES, "send a message at a time"),
        _component("saccade", misc.plan_saccade, ["saccade", "sbm:saccade"], misc.SACCADE_ATTRIBUTES,
                   "saccade mode: talk, listen, think"),
        _component("noise", misc.plan_noise, ["sbm:noise", "noise"], misc.NOISE_ATTRIBUTES, "Perlin noise on joints"),
        _component("blinkemitter", misc.plan_blink_emitter, ["bmlt:blinkemitter"], misc.EMITTER_ATTRIBUTES,
                   "ASAP blink emitter"),
        _component("breathingemitter", misc.plan_breathing_emitter, ["bmlt:breathingemitter"], misc.EMITTER_ATTRIBUTES,
                   "ASAP breathing emitter"),
    ]
