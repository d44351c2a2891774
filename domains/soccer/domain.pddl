; Robot soccer (Sec. 5.2, Fig. 5.6; Sec. 5.5.2, Fig. 5.15): approach the ball, dribble it, go through way-points.
(define (domain soccer)
  (:requirements :strips :typing)
  (:types pos)
  (:predicates
    (robot ?p - pos)        ; the robot is at p
    (ball ?p - pos)         ; the ball lies at p
    (atball ?p - pos)       ; the robot has the ball at p
    (final ?p - pos)        ; p is the target pose
    (waypoint ?p - pos)     ; p is a way-point to pass
    (next ?p ?q - pos)      ; q is the way-point that follows p
    (visited ?p - pos))     ; the robot has passed p

  (:action approachball
    :parameters (?from ?to - pos)
    :precondition (and (robot ?from) (ball ?to))
    :effect (and (atball ?to) (not (robot ?from))))

  (:action dribbleball
    :parameters (?from ?to - pos)
    :precondition (atball ?from)
    :effect (and (atball ?to) (not (atball ?from))))

  (:action gotopose
    :parameters (?from ?to - pos)
    :precondition (and (robot ?from) (waypoint ?to) (next ?from ?to))
    :effect (and (robot ?to) (visited ?to) (not (robot ?from)))))
