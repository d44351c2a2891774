; Service robotics (Sec. 5.5, Fig. 5.5, Fig. 5.11): a B21 moves cups between tables with goto, grip and put.
; A spot is a place where the B21 may stand: its start pose, or in front of a table to grip one cup (pickup)
; or to put one down (dropoff). Each visit to a table is its own spot, so each has its own free pose
; (Fig. 5.12: position along the table's edge, distance to it, heading), chosen by subgoal refinement. The two
; rooms meet at a door: the B21 crosses it with `cross` to a door spot, a way-point it passes without stopping
; (Sec. 5.5: its position across the door, heading and speed are free), one door spot per crossing.
(define (domain kitchen)
  (:requirements :strips :typing)
  (:types spot furniture cup room)
  (:predicates
    (robot ?s - spot)              ; the B21 stands at (or passes) spot s
    (in ?s - spot ?r - room)       ; spot s lies in room r (a door spot: in the room its crossing leads to)
    (door ?s - spot ?from ?to - room) ; spot s is in the door, crossing it leads from room from to room to
    (unused ?s - spot)             ; door spot s is still to be crossed (each crossing has its own spot)
    (table ?t - furniture)          ; t is a table cups can stand on
    (serves ?s - spot ?t - furniture) ; spot s lies in front of table t
    (on ?c - cup ?t - furniture)   ; cup c stands on table t
    (pickup ?s - spot ?c - cup)    ; from spot s the B21 can grip cup c (40-80 cm from the table's edge)
    (dropoff ?s - spot ?c - cup)   ; from spot s the B21 can put cup c at its put location
    (holding ?c - cup)             ; the B21 holds c in its gripper
    (handempty))                   ; the gripper is free

  (:action goto
    :parameters (?from ?to - spot ?r - room ?t - furniture)
    :precondition (and (robot ?from) (in ?from ?r) (in ?to ?r) (serves ?to ?t))
    :effect (and (robot ?to) (not (robot ?from))))

  (:action cross
    :parameters (?from ?to - spot ?r1 ?r2 - room)
    :precondition (and (robot ?from) (in ?from ?r1) (door ?to ?r1 ?r2) (unused ?to))
    :effect (and (robot ?to) (not (robot ?from)) (not (unused ?to))))

  (:action grip
    :parameters (?c - cup ?s - spot ?t - furniture)
    :precondition (and (robot ?s) (table ?t) (serves ?s ?t) (on ?c ?t) (pickup ?s ?c) (handempty))
    :effect (and (holding ?c) (not (on ?c ?t)) (not (handempty))))

  (:action put
    :parameters (?c - cup ?s - spot ?t - furniture)
    :precondition (and (robot ?s) (table ?t) (serves ?s ?t) (holding ?c) (dropoff ?s ?c))
    :effect (and (on ?c ?t) (handempty) (not (holding ?c)))))
