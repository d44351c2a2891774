; The three-operator blocks world (IPC "blocksworld 3ops"): a block moves in one step, there is no hand,
; so towers that share no block can be rebuilt in parallel.
(define (domain blocks3)
  (:requirements :strips :typing)
  (:types block)
  (:predicates (on ?x ?y - block) (ontable ?x - block) (clear ?x - block))
  (:action move-b-to-b
    :parameters (?b ?from ?to - block)
    :precondition (and (clear ?b) (clear ?to) (on ?b ?from))
    :effect (and (on ?b ?to) (clear ?from) (not (on ?b ?from)) (not (clear ?to))))
  (:action move-b-to-t
    :parameters (?b ?from - block)
    :precondition (and (clear ?b) (on ?b ?from))
    :effect (and (ontable ?b) (clear ?from) (not (on ?b ?from))))
  (:action move-t-to-b
    :parameters (?b ?to - block)
    :precondition (and (clear ?b) (clear ?to) (ontable ?b))
    :effect (and (on ?b ?to) (not (clear ?to)) (not (ontable ?b)))))
