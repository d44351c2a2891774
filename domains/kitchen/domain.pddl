; Service robotics (Sec. 5.5, Fig. 5.5, Fig. 5.11): a B21 moves cups between tables with goto, grip and put.
(define (domain kitchen)
  (:requirements :strips :typing)
  (:types location cup)
  (:predicates
    (robot ?l - location)          ; the B21 stands at l (its start pose or in front of a table)
    (table ?l - location)          ; l is a table cups can be put on
    (on ?c - cup ?l - location)    ; cup c stands on table l
    (holding ?c - cup)             ; the B21 holds c in its gripper
    (handempty))                   ; the gripper is free

  (:action goto
    :parameters (?from ?to - location)
    :precondition (robot ?from)
    :effect (and (robot ?to) (not (robot ?from))))

  (:action grip
    :parameters (?c - cup ?l - location)
    :precondition (and (robot ?l) (table ?l) (on ?c ?l) (handempty))
    :effect (and (holding ?c) (not (on ?c ?l)) (not (handempty))))

  (:action put
    :parameters (?c - cup ?l - location)
    :precondition (and (robot ?l) (table ?l) (holding ?c))
    :effect (and (on ?c ?l) (handempty) (not (holding ?c)))))
